#include "dense_slam.h"

#include "../property_checks.h"

#include <camera/pinhole_camera.h>
#include <slam/tsdf_capacity.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "../convert/image_convert.h"
#include "../convert/mesh_convert.h"
#include "../convert/pose_convert.h"

using namespace godot;

namespace roomprobe {

namespace {

DenseSLAM::TrackingState to_node_state(TrackingState p_state) {
	switch (p_state) {
		case TrackingState::Good:
			return DenseSLAM::TRACKING_GOOD;
		case TrackingState::Poor:
			return DenseSLAM::TRACKING_POOR;
		case TrackingState::Lost:
			break;
	}
	return DenseSLAM::TRACKING_LOST;
}

// Godot's arrays of the dense mesh, with its vertex colours. Bulk copies: this runs on the main
// thread whenever the mesh changes, and the mesh has hundreds of thousands of vertices.
Array to_surface_arrays(const TriangleMesh &p_mesh) {
	static_assert(sizeof(glm::vec3) == sizeof(Vector3), "glm::vec3 and Vector3 are both three floats");
	PackedVector3Array vertices, normals;
	PackedColorArray colors;
	const int64_t n = int64_t(p_mesh.vertices.size());
	vertices.resize(n);
	normals.resize(n);
	colors.resize(n);
	// Vector3 has constructors but is three floats, as glm::vec3 is: a byte copy is exact.
	std::memcpy(static_cast<void *>(vertices.ptrw()), p_mesh.vertices.data(), size_t(n) * sizeof(Vector3));
	std::memcpy(static_cast<void *>(normals.ptrw()), p_mesh.normals.data(), size_t(n) * sizeof(Vector3));
	Color *c = colors.ptrw();
	for (int64_t i = 0; i < n; i++) {
		const glm::u8vec3 &v = p_mesh.colors[size_t(i)];
		c[i] = Color(v.x / 255.0f, v.y / 255.0f, v.z / 255.0f);
	}
	Array arrays = triangle_surface_arrays(vertices, normals, p_mesh.indices);
	arrays[Mesh::ARRAY_COLOR] = colors;
	return arrays;
}

} // namespace

DenseSLAM::DenseSLAM() {
	mesh.instantiate();
	// After RigCapture (which applies the engine's configuration) and before the others.
	set_process_priority(-20);
}

namespace {

// The AR background: a full-screen quad just in front of the far plane (Godot's reverse Z: 0 is
// far), so every virtual object draws over it, with the camera image (8-bit sRGB, decoded here and
// encoded again on output: the same pixels under the default linear tone mapping).
const char *const BACKGROUND_SHADER_CODE = R"(shader_type spatial;
render_mode unshaded, cull_disabled, shadows_disabled, depth_draw_never;
uniform sampler2D image : source_color, filter_linear;
void vertex() {
	POSITION = vec4(VERTEX.xy, 1e-6, 1.0);
}
void fragment() {
	ALBEDO = texture(image, UV).rgb;
}
)";

} // namespace

DenseSLAM::~DenseSLAM() {
	disconnect_engine();
}

void DenseSLAM::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY && mesh_root == nullptr) {
		// An internal child: not saved with the scene, not listed in the editor. It holds one
		// MeshInstance3D per region of the dense mesh.
		mesh_root = memnew(Node3D);
		material.instantiate();
		// The vertex colours are the surfaces' observed light, as the coarse atlas is.
		material->set_shading_mode(BaseMaterial3D::SHADING_MODE_UNSHADED);
		material->set_flag(BaseMaterial3D::FLAG_ALBEDO_FROM_VERTEX_COLOR, true);
		add_child(mesh_root, false, Node::INTERNAL_MODE_FRONT);
		// The model is in world coordinates.
		mesh_root->set_as_top_level(true);
		set_process(!Engine::get_singleton()->is_editor_hint());
	}
	if (p_what == NOTIFICATION_READY) {
		update_background();
		connect_engine();
	} else if (p_what == NOTIFICATION_EXIT_TREE) {
		disconnect_engine();
	}
}

void DenseSLAM::_process(double p_delta) {
	(void)p_delta;
	MainThreadTimer timer(MainThreadTimer::DENSE_SLAM);
	process_rig_frame();
}

// ---------------------------------------------------------------- the engine

void DenseSLAM::connect_engine() {
	std::string unused; // get_warnings() reports it
	Node *capture = find_collaborator(*this, capture_path, "RigCapture", "capture", &unused);
	std::shared_ptr<LiveRoom> found = live_room_of(capture);
	if (found == engine) {
		return;
	}
	disconnect_engine();
	engine = found;
	taken_sequence = taken_mesh = 0;
	push_settings();
}

void DenseSLAM::disconnect_engine() {
	if (engine) {
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.dense = false; });
		engine.reset();
	}
}

bool DenseSLAM::settings_valid() const {
	const double min_depth_m = roomprobe::IcpOptions().min_depth_m;
	return voxel_size > 0.0 && truncation_distance > voxel_size && max_blocks >= 1 && max_blocks <= (1 << 22) && colour_weight >= 0.0 &&
			colour_weight <= 100.0 && tracking_max_depth > min_depth_m && tracking_max_depth <= 100.0 && fusion_max_depth > min_depth_m &&
			fusion_max_depth <= 100.0;
}

// The volume's settings into the engine (applied by RigCapture, which restarts the model).
void DenseSLAM::push_settings() {
	if (!engine) {
		return;
	}
	const bool valid = settings_valid();
	engine->edit_config([&](LiveRoomConfig &p_config) {
		p_config.dense = valid;
		p_config.dense_poses = roomprobe::PoseSource::Tracked;
		p_config.slam.tsdf.voxel_size_m = float(voxel_size);
		p_config.slam.tsdf.truncation_m = float(truncation_distance);
		p_config.slam.tsdf.max_blocks = max_blocks;
		p_config.slam.icp.colour_weight = colour_weight;
		p_config.slam.icp.max_depth_m = tracking_max_depth;
		p_config.slam.tsdf.max_depth_m = float(fusion_max_depth);
		p_config.mesh_interval_frames = std::max(1, mesh_update_interval);
	});
	update_configuration_warnings();
}

// ---------------------------------------------------------------- properties

void DenseSLAM::set_capture_path(const NodePath &p_path) {
	capture_path = p_path;
	if (is_inside_tree()) {
		connect_engine();
	}
	update_configuration_warnings();
}

NodePath DenseSLAM::get_capture_path() const { return capture_path; }
void DenseSLAM::set_camera_path(const NodePath &p_path) { camera_path = p_path; }

// The camera that follows the tracked pose: camera's node, or with none set the viewport's current
// Camera3D while the game runs (the editor's view is never moved).
Node3D *DenseSLAM::driven_camera() const {
	if (!camera_path.is_empty()) {
		return cast_to<Node3D>(get_node_or_null(camera_path));
	}
	if (!is_inside_tree() || Engine::get_singleton()->is_editor_hint() || get_viewport() == nullptr) {
		return nullptr;
	}
	return get_viewport()->get_camera_3d();
}
NodePath DenseSLAM::get_camera_path() const { return camera_path; }
void DenseSLAM::set_coarse_model_path(const NodePath &p_path) { coarse_model_path = p_path; }
NodePath DenseSLAM::get_coarse_model_path() const { return coarse_model_path; }

void DenseSLAM::set_voxel_size(double p_metres) {
	voxel_size = property_checks::clamped("DenseSLAM.voxel_size", p_metres, 0.002, 0.1, voxel_size, " m");
	push_settings();
}

double DenseSLAM::get_voxel_size() const { return voxel_size; }

void DenseSLAM::set_truncation_distance(double p_metres) {
	truncation_distance = property_checks::clamped("DenseSLAM.truncation_distance", p_metres, 0.005, 0.5, truncation_distance, " m");
	push_settings();
}

double DenseSLAM::get_truncation_distance() const { return truncation_distance; }

void DenseSLAM::set_colour_weight(double p_metres_per_intensity) {
	colour_weight = property_checks::clamped("DenseSLAM.colour_weight", p_metres_per_intensity, 0.0, 100.0, colour_weight);
	push_settings();
}

double DenseSLAM::get_colour_weight() const { return colour_weight; }

void DenseSLAM::set_tracking_max_depth(double p_metres) {
	tracking_max_depth = property_checks::clamped("DenseSLAM.tracking_max_depth", p_metres, 0.5, 100.0, tracking_max_depth, " m");
	push_settings();
}

double DenseSLAM::get_tracking_max_depth() const { return tracking_max_depth; }

void DenseSLAM::set_fusion_max_depth(double p_metres) {
	fusion_max_depth = property_checks::clamped("DenseSLAM.fusion_max_depth", p_metres, 0.5, 100.0, fusion_max_depth, " m");
	push_settings();
}

double DenseSLAM::get_fusion_max_depth() const { return fusion_max_depth; }

void DenseSLAM::set_max_blocks(int64_t p_blocks) {
	const int blocks = int(property_checks::clamped_int("DenseSLAM.max_blocks", p_blocks, 1, 4194304));
	// A cap whose full model would not fit in this machine's memory is refused, naming the memory
	// it needs (issue #38: the top of the range ended in std::bad_alloc when the model was made).
	const std::string too_big = roomprobe::tsdf_capacity_problem("DenseSLAM.max_blocks", blocks, roomprobe::physical_memory_bytes());
	if (!too_big.empty()) {
		ERR_PRINT(String((too_big + "; left at " + std::to_string(max_blocks)).c_str()));
		return;
	}
	max_blocks = blocks;
	push_settings();
}

int DenseSLAM::get_max_blocks() const { return max_blocks; }

void DenseSLAM::set_mesh_layers(int64_t p_layers) {
	mesh_layers = property_checks::render_layers("DenseSLAM.mesh_layers", p_layers);
	masked_camera = 0; // the AR camera's mask is looked at again
	for (auto &[region, view] : chunk_views) {
		view.instance->set_layer_mask(mesh_layers);
	}
}

uint32_t DenseSLAM::get_mesh_layers() const { return mesh_layers; }

void DenseSLAM::set_mesh_update_interval(int64_t p_frames) {
	mesh_update_interval = int(property_checks::clamped_int("DenseSLAM.mesh_update_interval", p_frames, 1, 300, " frames"));
	push_settings();
}

int DenseSLAM::get_mesh_update_interval() const { return mesh_update_interval; }
void DenseSLAM::set_mesh_upload_budget(int64_t p_triangles) {
	mesh_upload_budget = int(property_checks::clamped_int("DenseSLAM.mesh_upload_budget", p_triangles, 0, 1000000, " triangles"));
}
int DenseSLAM::get_mesh_upload_budget() const { return mesh_upload_budget; }

// ---------------------------------------------------------------- results

void DenseSLAM::set_state(TrackingState p_state, const std::string &p_reason) {
	const bool changed = p_state != tracking_state;
	tracking_state = p_state;
	tracking_reason = p_reason;
	if (changed) {
		emit_signal("tracking_state_changed", p_state, String(p_reason.c_str()));
	}
}

bool DenseSLAM::process_rig_frame() {
	if (!engine && is_inside_tree()) {
		connect_engine(); // the RigCapture may have come later
	}
	if (!engine) {
		return false;
	}
	take_mesh();
	const std::shared_ptr<const TrackedFrame> frame = engine->tracked_frame();
	if (!frame || frame->sequence == taken_sequence || !engine->has_dense()) {
		return false;
	}
	taken_sequence = frame->sequence;
	last_frame = frame;
	processed++;
	set_state(to_node_state(frame->state), frame->reason);
	// The pose and the image of one frame: the background and the virtual objects stay in register.
	Node3D *camera = frame->has_pose ? driven_camera() : nullptr;
	ERR_FAIL_COND_V_MSG(frame->has_pose && camera == nullptr && !camera_path.is_empty(), true, "DenseSLAM.camera does not lead to a Node3D.");
	if (camera != nullptr) {
		camera->set_global_transform(camera_transform_from_pose(frame->world_from_camera));
		// The AR camera sees what the RGB camera saw: its field of view from the rig.
		Camera3D *ar_camera = cast_to<Camera3D>(camera);
		const double fov = pinhole_vertical_fov_degrees(engine->rgb_camera());
		if (ar_camera != nullptr && fov > 0.0 && std::abs(ar_camera->get_fov() - fov) > 1e-4) {
			ar_camera->set_fov(fov);
		}
		// It shows the video, not the models of the real room: their layers are off its mask
		// (the probes and a driven ReflectionProbe still see them). Looked at again only when the
		// camera or its mask is not what it was left as (finding the room may walk the scene).
		if (ar_camera != nullptr && (ar_camera->get_instance_id() != masked_camera || ar_camera->get_cull_mask() != masked_camera_mask)) {
			std::string unused;
			Node *room = find_collaborator(*this, coarse_model_path, "CoarseRoomModel", "coarse_model", &unused);
			const uint32_t hidden = mesh_layers | (room != nullptr ? uint32_t(int64_t(room->get("room_layers"))) : 0u);
			ar_camera->set_cull_mask(ar_camera->get_cull_mask() & ~hidden);
			masked_camera = ar_camera->get_instance_id();
			masked_camera_mask = ar_camera->get_cull_mask();
		}
	}
	if (camera_image_wanted && !frame->rgba.empty()) {
		show_in_texture(image_from_buffer(frame->rgba), camera_image);
		const Ref<ShaderMaterial> shown = background != nullptr ? Ref<ShaderMaterial>(background->get_material_override()) : Ref<ShaderMaterial>();
		if (shown.is_valid() && shown->get_shader_parameter("image") != Variant(camera_image)) {
			shown->set_shader_parameter("image", camera_image); // the texture is made with the first image
		}
	}
	emit_signal("frame_processed", int64_t(frame->sequence));
	return true;
}

void DenseSLAM::set_camera_background(bool p_enabled) {
	camera_background = p_enabled;
	if (is_inside_tree()) {
		update_background();
	}
}

bool DenseSLAM::get_camera_background() const { return camera_background; }

void DenseSLAM::update_background() {
	if (!camera_background || Engine::get_singleton()->is_editor_hint()) {
		if (background != nullptr) {
			background->queue_free();
			background = nullptr;
		}
		return;
	}
	if (background != nullptr) {
		return;
	}
	PackedVector3Array corners;
	PackedVector2Array uvs;
	for (const auto &[x, y] : { std::pair{ -1.0f, -1.0f }, { 1.0f, -1.0f }, { 1.0f, 1.0f }, { -1.0f, 1.0f } }) {
		corners.push_back(Vector3(x, y, 0.0f));
		uvs.push_back(Vector2(0.5f * (x + 1.0f), 0.5f * (1.0f + y))); // POSITION's y grows down the screen (Vulkan)
	}
	PackedInt32Array indices;
	for (int i : { 0, 2, 1, 0, 3, 2 }) {
		indices.push_back(i);
	}
	Array arrays;
	arrays.resize(Mesh::ARRAY_MAX);
	arrays[Mesh::ARRAY_VERTEX] = corners;
	arrays[Mesh::ARRAY_TEX_UV] = uvs;
	arrays[Mesh::ARRAY_INDEX] = indices;
	Ref<ArrayMesh> quad;
	quad.instantiate();
	quad->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, arrays);
	Ref<Shader> shader;
	shader.instantiate();
	shader->set_code(BACKGROUND_SHADER_CODE);
	Ref<ShaderMaterial> background_material;
	background_material.instantiate();
	background_material->set_shader(shader);
	background_material->set_shader_parameter("image", get_camera_image_texture());
	background = memnew(MeshInstance3D);
	background->set_mesh(quad);
	background->set_material_override(background_material);
	background->set_cast_shadows_setting(GeometryInstance3D::SHADOW_CASTING_SETTING_OFF);
	// Never culled: its vertices are placed in clip space, not where its box says.
	background->set_custom_aabb(AABB{ Vector3(-1e5f, -1e5f, -1e5f), Vector3(2e5f, 2e5f, 2e5f) });
	add_child(background, false, Node::INTERNAL_MODE_FRONT);
}

Ref<ImageTexture> DenseSLAM::get_camera_image_texture() const {
	if (!camera_image_wanted) {
		camera_image_wanted = true;
		if (last_frame && !last_frame->rgba.empty()) {
			show_in_texture(image_from_buffer(last_frame->rgba), camera_image);
		}
	}
	return camera_image;
}

void DenseSLAM::take_mesh() {
	const std::shared_ptr<const DenseMeshSnapshot> snapshot = engine ? engine->dense_mesh() : nullptr;
	if (snapshot && snapshot != shown_mesh) {
		shown_mesh = snapshot;
	}
	show_chunks();
	if (shown_mesh && shown_mesh->version != taken_mesh) {
		taken_mesh = shown_mesh->version;
		emit_signal("mesh_updated");
	}
}

// Brings the displayed regions up to the newest snapshot: regions gone are removed at once;
// changed ones are converted until mesh_upload_budget triangles this frame, the rest next frame.
void DenseSLAM::show_chunks() {
	if (mesh_root == nullptr || !shown_mesh) {
		return;
	}
	std::map<glm::ivec3, const DenseMeshChunk *, IvecLess> current;
	for (const DenseMeshChunk &chunk : shown_mesh->chunks) {
		current[chunk.region] = &chunk;
	}
	for (auto it = chunk_views.begin(); it != chunk_views.end();) {
		if (current.count(it->first) == 0) {
			it->second.instance->queue_free();
			it = chunk_views.erase(it);
		} else {
			++it;
		}
	}
	size_t uploaded = 0;
	for (const auto &[region, chunk] : current) {
		ChunkView &view = chunk_views[region];
		if (view.version == chunk->version) {
			continue;
		}
		if (mesh_upload_budget > 0 && uploaded >= size_t(mesh_upload_budget)) {
			break;
		}
		if (view.instance == nullptr) {
			view.instance = memnew(MeshInstance3D);
			view.instance->set_layer_mask(mesh_layers);
			view.instance->set_material_override(material);
			mesh_root->add_child(view.instance, false, Node::INTERNAL_MODE_FRONT);
		}
		Ref<ArrayMesh> piece;
		piece.instantiate();
		piece->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, to_surface_arrays(*chunk->mesh));
		view.instance->set_mesh(piece);
		view.version = chunk->version;
		uploaded += chunk->mesh->indices.size() / 3;
	}
}

void DenseSLAM::update_mesh() {
	if (!engine) {
		return;
	}
	engine->update_dense_mesh();
	// Asked for explicitly: every region now, whatever the per-frame budget.
	const int budget = mesh_upload_budget;
	mesh_upload_budget = 0;
	take_mesh();
	mesh_upload_budget = budget;
}

void DenseSLAM::reset() {
	if (engine) {
		// The whole live model starts again (tracking, volume, and the coarse texture with it).
		engine->edit_config([](LiveRoomConfig &) {});
		engine->apply_config();
	}
	for (auto &[region, view] : chunk_views) {
		view.instance->queue_free();
	}
	chunk_views.clear();
	shown_mesh.reset();
	mesh->clear_surfaces();
	last_frame.reset();
	taken_sequence = taken_mesh = 0;
	processed = 0;
	set_state(TRACKING_NOT_STARTED, "");
}

DenseSLAM::TrackingState DenseSLAM::get_tracking_state() const { return tracking_state; }
String DenseSLAM::get_tracking_reason() const { return String(tracking_reason.c_str()); }

Transform3D DenseSLAM::get_camera_transform() const {
	return last_frame && last_frame->has_pose ? camera_transform_from_pose(last_frame->world_from_camera) : Transform3D();
}

int64_t DenseSLAM::get_processed_frame_count() const { return processed; }

Dictionary DenseSLAM::get_stats() const {
	Dictionary d;
	if (!engine || !last_frame) {
		return d;
	}
	const LiveRoomStats s = engine->stats();
	d.set("frames", int64_t(s.dense_frames));
	d.set("integrated_frames", int64_t(s.dense_fused));
	d.set("dropped_frames", int64_t(s.rgbd_dropped));
	d.set("allocated_blocks", int64_t(s.tsdf.allocated_blocks));
	d.set("capacity_blocks", int64_t(s.tsdf.capacity_blocks));
	d.set("bytes_used", int64_t(s.tsdf.bytes_used));
	d.set("evicted_blocks", int64_t(s.tsdf.evicted_blocks_total));
	d.set("bounds", AABB{ to_godot(glm::dvec3(s.tsdf.bounds_min)), to_godot(glm::dvec3(s.tsdf.bounds_max - s.tsdf.bounds_min)) });
	d.set("track_ms", last_frame->timings.track_ms);
	d.set("integrate_ms", last_frame->timings.integrate_ms);
	d.set("raycast_ms", last_frame->timings.raycast_ms);
	d.set("frame_ms", last_frame->timings.frame_ms);
	d.set("inlier_fraction", last_frame->inlier_fraction);
	d.set("rmse_m", last_frame->rmse_m);
	d.set("constraint", last_frame->constraint);
	d.set("colour_used", last_frame->colour_used);
	d.set("relocalisation_attempts", int64_t(s.relocalisation_attempts));
	d.set("relocalisations", int64_t(s.relocalisations));
	d.set("keyframes", int64_t(s.keyframes));
	d.set("keyframe_relocalisations", int64_t(s.keyframe_relocalisations));
	d.set("latency_ms_p50", s.rgbd_latency.p50_ms);
	d.set("latency_ms_p95", s.rgbd_latency.p95_ms);
	return d;
}

// The whole mesh as one surface, converted on request (scripts, tests): the display itself uses
// the regions (show_chunks), so this costs nothing unless asked for.
Ref<ArrayMesh> DenseSLAM::get_mesh() const {
	if (shown_mesh && shown_mesh->version != whole_mesh_version) {
		whole_mesh_version = shown_mesh->version;
		mesh->clear_surfaces();
		if (shown_mesh->mesh && !shown_mesh->mesh->indices.empty()) {
			mesh->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, to_surface_arrays(*shown_mesh->mesh));
		}
	}
	return mesh;
}

// ---------------------------------------------------------------- placement (Embree)

// A bad argument is an error and a Dictionary holding only "error", so that it is never read as
// "nothing hit" (an empty Dictionary).
static Dictionary placement_refused(const std::string &p_message) {
	ERR_PRINT(String(("DenseSLAM: " + p_message).c_str()));
	Dictionary d;
	d.set("error", String(p_message.c_str()));
	return d;
}

static bool is_finite(const Vector3 &p_v) { return std::isfinite(p_v.x) && std::isfinite(p_v.y) && std::isfinite(p_v.z); }

static std::string text(const Vector3 &p_v) {
	char out[96];
	std::snprintf(out, sizeof(out), "(%g, %g, %g)", p_v.x, p_v.y, p_v.z);
	return out;
}

Dictionary DenseSLAM::place_on_ray(const Vector3 &p_origin, const Vector3 &p_direction) const {
	if (!is_finite(p_origin) || !is_finite(p_direction)) {
		return placement_refused("place_on_ray: origin " + text(p_origin) + " and direction " + text(p_direction) + " must be finite");
	}
	if (p_direction.dot(p_direction) < 1e-12f) {
		return placement_refused("place_on_ray: direction " + text(p_direction) + " is zero; give the ray's direction");
	}
	Dictionary d;
	if (!engine) {
		return d;
	}
	const PlacementHit hit = engine->place_ray(to_glm(p_origin), to_glm(p_direction));
	if (hit.surface == PlacementSurface::None) {
		return d;
	}
	d.set("position", to_godot(hit.point));
	d.set("normal", to_godot(hit.normal));
	d.set("surface", String(hit.surface == PlacementSurface::Dense ? "dense" : "coarse"));
	d.set("distance", hit.distance_m);
	return d;
}

Dictionary DenseSLAM::place_on_surface(const Vector2 &p_screen_position) const {
	const Camera3D *camera = cast_to<Camera3D>(driven_camera());
	ERR_FAIL_NULL_V_MSG(camera, Dictionary(), camera_path.is_empty() ? "DenseSLAM.place_on_surface needs a camera: set camera, or make a Camera3D current" : "DenseSLAM.camera does not lead to a Camera3D.");
	// Far off-screen the camera's ray still goes somewhere, and once returned a hit no one could
	// see: a point outside the viewport is refused.
	const Rect2 visible = camera->get_viewport()->get_visible_rect();
	const Vector2 &p = p_screen_position;
	const bool inside = p.x >= visible.position.x && p.y >= visible.position.y && p.x < visible.position.x + visible.size.x &&
			p.y < visible.position.y + visible.size.y; // false for NaN too
	if (!inside) {
		char out[192];
		std::snprintf(out, sizeof(out), "place_on_surface: screen_position (%g, %g) is outside the camera's viewport (%g x %g pixels)", p.x,
				p.y, visible.size.x, visible.size.y);
		return placement_refused(out);
	}
	return place_on_ray(camera->project_ray_origin(p_screen_position), camera->project_ray_normal(p_screen_position));
}

PackedStringArray DenseSLAM::get_warnings() const {
	PackedStringArray warnings;
	std::string warning;
	const Node *capture = is_inside_tree() ? find_collaborator(*this, capture_path, "RigCapture", "capture", &warning) : nullptr;
	if (!warning.empty()) {
		warnings.push_back(String(warning.c_str()));
	} else if (!is_inside_tree()) {
		warnings.push_back("Not in a scene: it takes its RGB-D frames from the RigCapture of its scene (or the one capture leads to).");
	} else if (capture == nullptr) {
		warnings.push_back("No RigCapture in the scene: add one, or set capture to it.");
	}
	if (!settings_valid()) {
		warnings.push_back("RGB-D frames are not being processed: voxel_size must be > 0, truncation_distance larger than voxel_size, max_blocks in 1..4194304, colour_weight in 0..100, tracking_max_depth and fusion_max_depth above 0.3 m and at most 100 m.");
	}
	// Without a rig yet (the editor, or before the RigCapture opens its recording) the engine says
	// dense SLAM needs one: not this node's problem while a RigCapture is there; it says its own.
	const bool rig_to_come = capture != nullptr && engine && !engine->config().has_rig;
	if (engine && !engine->config_pending() && !engine->configuration_error().empty() && !rig_to_come) {
		warnings.push_back(String(("RGB-D frames are not being processed: " + engine->configuration_error()).c_str()));
	}
	if (!camera_path.is_empty() && is_inside_tree() && cast_to<Camera3D>(get_node_or_null(camera_path)) == nullptr) {
		warnings.push_back("camera does not lead to a Camera3D.");
	}
	return warnings;
}

void DenseSLAM::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &DenseSLAM::get_warnings);
	ClassDB::bind_method(D_METHOD("set_capture", "path"), &DenseSLAM::set_capture_path);
	ClassDB::bind_method(D_METHOD("get_capture"), &DenseSLAM::get_capture_path);
	ClassDB::bind_method(D_METHOD("set_camera", "path"), &DenseSLAM::set_camera_path);
	ClassDB::bind_method(D_METHOD("get_camera"), &DenseSLAM::get_camera_path);
	ClassDB::bind_method(D_METHOD("set_coarse_model", "path"), &DenseSLAM::set_coarse_model_path);
	ClassDB::bind_method(D_METHOD("get_coarse_model"), &DenseSLAM::get_coarse_model_path);
	ClassDB::bind_method(D_METHOD("set_colour_weight", "metres_per_intensity"), &DenseSLAM::set_colour_weight);
	ClassDB::bind_method(D_METHOD("get_colour_weight"), &DenseSLAM::get_colour_weight);
	ClassDB::bind_method(D_METHOD("set_tracking_max_depth", "metres"), &DenseSLAM::set_tracking_max_depth);
	ClassDB::bind_method(D_METHOD("get_tracking_max_depth"), &DenseSLAM::get_tracking_max_depth);
	ClassDB::bind_method(D_METHOD("set_fusion_max_depth", "metres"), &DenseSLAM::set_fusion_max_depth);
	ClassDB::bind_method(D_METHOD("get_fusion_max_depth"), &DenseSLAM::get_fusion_max_depth);
	ClassDB::bind_method(D_METHOD("set_voxel_size", "metres"), &DenseSLAM::set_voxel_size);
	ClassDB::bind_method(D_METHOD("get_voxel_size"), &DenseSLAM::get_voxel_size);
	ClassDB::bind_method(D_METHOD("set_truncation_distance", "metres"), &DenseSLAM::set_truncation_distance);
	ClassDB::bind_method(D_METHOD("get_truncation_distance"), &DenseSLAM::get_truncation_distance);
	ClassDB::bind_method(D_METHOD("set_max_blocks", "blocks"), &DenseSLAM::set_max_blocks);
	ClassDB::bind_method(D_METHOD("get_max_blocks"), &DenseSLAM::get_max_blocks);
	ClassDB::bind_method(D_METHOD("set_mesh_layers", "layers"), &DenseSLAM::set_mesh_layers);
	ClassDB::bind_method(D_METHOD("get_mesh_layers"), &DenseSLAM::get_mesh_layers);
	ClassDB::bind_method(D_METHOD("set_mesh_update_interval", "frames"), &DenseSLAM::set_mesh_update_interval);
	ClassDB::bind_method(D_METHOD("get_mesh_update_interval"), &DenseSLAM::get_mesh_update_interval);
	ClassDB::bind_method(D_METHOD("set_mesh_upload_budget", "triangles"), &DenseSLAM::set_mesh_upload_budget);
	ClassDB::bind_method(D_METHOD("get_mesh_upload_budget"), &DenseSLAM::get_mesh_upload_budget);
	ClassDB::bind_method(D_METHOD("process_rig_frame"), &DenseSLAM::process_rig_frame);
	ClassDB::bind_method(D_METHOD("get_camera_image_texture"), &DenseSLAM::get_camera_image_texture);
	ClassDB::bind_method(D_METHOD("set_camera_background", "enabled"), &DenseSLAM::set_camera_background);
	ClassDB::bind_method(D_METHOD("get_camera_background"), &DenseSLAM::get_camera_background);
	ClassDB::bind_method(D_METHOD("get_tracking_state"), &DenseSLAM::get_tracking_state);
	ClassDB::bind_method(D_METHOD("get_tracking_reason"), &DenseSLAM::get_tracking_reason);
	ClassDB::bind_method(D_METHOD("get_camera_transform"), &DenseSLAM::get_camera_transform);
	ClassDB::bind_method(D_METHOD("get_processed_frame_count"), &DenseSLAM::get_processed_frame_count);
	ClassDB::bind_method(D_METHOD("get_stats"), &DenseSLAM::get_stats);
	ClassDB::bind_method(D_METHOD("get_mesh"), &DenseSLAM::get_mesh);
	ClassDB::bind_method(D_METHOD("update_mesh"), &DenseSLAM::update_mesh);
	ClassDB::bind_method(D_METHOD("reset"), &DenseSLAM::reset);
	ClassDB::bind_method(D_METHOD("place_on_ray", "origin", "direction"), &DenseSLAM::place_on_ray);
	ClassDB::bind_method(D_METHOD("place_on_surface", "screen_position"), &DenseSLAM::place_on_surface);

	ADD_GROUP("Sources", "");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "capture", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "RigCapture"), "set_capture", "get_capture");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "coarse_model", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "CoarseRoomModel"), "set_coarse_model", "get_coarse_model");
	ADD_GROUP("AR Camera", "");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "camera", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "Camera3D"), "set_camera", "get_camera");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "camera_background"), "set_camera_background", "get_camera_background");
	ADD_GROUP("Volume", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "voxel_size", PROPERTY_HINT_RANGE, "0.002,0.1,0.001,suffix:m"), "set_voxel_size", "get_voxel_size");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "truncation_distance", PROPERTY_HINT_RANGE, "0.005,0.5,0.001,suffix:m"), "set_truncation_distance", "get_truncation_distance");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "max_blocks", PROPERTY_HINT_RANGE, "1,4194304,1"), "set_max_blocks", "get_max_blocks");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "colour_weight", PROPERTY_HINT_RANGE, "0,100,0.01,exp"), "set_colour_weight", "get_colour_weight");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "tracking_max_depth", PROPERTY_HINT_RANGE, "0.5,100,0.1,exp,suffix:m"), "set_tracking_max_depth", "get_tracking_max_depth");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "fusion_max_depth", PROPERTY_HINT_RANGE, "0.5,100,0.1,exp,suffix:m"), "set_fusion_max_depth", "get_fusion_max_depth");
	ADD_GROUP("Mesh", "mesh_");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "mesh_layers", PROPERTY_HINT_LAYERS_3D_RENDER), "set_mesh_layers", "get_mesh_layers");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "mesh_update_interval", PROPERTY_HINT_RANGE, "1,300,1,suffix:frames"), "set_mesh_update_interval", "get_mesh_update_interval");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "mesh_upload_budget", PROPERTY_HINT_RANGE, "0,1000000,1000,suffix:triangles"), "set_mesh_upload_budget", "get_mesh_upload_budget");

	BIND_ENUM_CONSTANT(TRACKING_NOT_STARTED);
	BIND_ENUM_CONSTANT(TRACKING_GOOD);
	BIND_ENUM_CONSTANT(TRACKING_POOR);
	BIND_ENUM_CONSTANT(TRACKING_LOST);

	ADD_SIGNAL(MethodInfo("tracking_state_changed", PropertyInfo(Variant::INT, "state"), PropertyInfo(Variant::STRING, "reason")));
	ADD_SIGNAL(MethodInfo("frame_processed", PropertyInfo(Variant::INT, "rgbd_frame")));
	ADD_SIGNAL(MethodInfo("mesh_updated"));
}

} // namespace roomprobe
