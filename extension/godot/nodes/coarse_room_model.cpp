// CoarseRoomModel (coarse_room_model.h): the node's life, its room and mesh, the atlas, the engine
// it gives the room to, the room file and the warnings. Its properties and bindings are in
// coarse_room_model_properties.cpp, the room found from a sweep in coarse_room_model_found_room.cpp
// (split by concern to keep each file short).
#include "coarse_room_model.h"

#include "../convert/image_convert.h"
#include "../convert/mesh_convert.h"
#include "../convert/pose_convert.h"
#include "../convert/project_paths.h"

#include <recording/room_file.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

using namespace godot;

namespace roomprobe {


namespace {

// The mesh's arrays in Godot's layout, with the atlas UVs.
Array to_surface_arrays(const RoomMesh &p_mesh) {
	PackedVector3Array vertices, normals;
	PackedVector2Array uvs;
	vertices.resize(int64_t(p_mesh.positions.size()));
	normals.resize(int64_t(p_mesh.normals.size()));
	uvs.resize(int64_t(p_mesh.uvs.size()));
	for (size_t i = 0; i < p_mesh.positions.size(); i++) {
		const Vec3f &p = p_mesh.positions[i];
		const Vec3f &n = p_mesh.normals[i];
		vertices[int64_t(i)] = Vector3(p.x, p.y, p.z);
		normals[int64_t(i)] = Vector3(n.x, n.y, n.z);
		uvs[int64_t(i)] = Vector2(p_mesh.uvs[i].x, p_mesh.uvs[i].y);
	}
	Array arrays = triangle_surface_arrays(vertices, normals, p_mesh.indices);
	arrays[Mesh::ARRAY_TEX_UV] = uvs;
	return arrays;
}

} // namespace

CoarseRoomModel::CoarseRoomModel() {
	mesh.instantiate();
	// After RigCapture (which delivers frames) and before RoomProbe (which renders the texture).
	set_process_priority(-10);
	// Built at once, so that a new node already reports why its (empty) floorplan is no room.
	rebuild();
}

CoarseRoomModel::~CoarseRoomModel() {
	stop_room_search();
	if (engine && !own_engine) {
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.has_room = false; });
	}
}

void CoarseRoomModel::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY && mesh_instance == nullptr) {
		// An internal child: it is not saved with the scene and the editor does not list it.
		mesh_instance = memnew(MeshInstance3D);
		mesh_instance->set_mesh(mesh);
		mesh_instance->set_layer_mask(room_layers);
		add_child(mesh_instance, false, Node::INTERNAL_MODE_FRONT);
		rebuild();
		apply_material();
		// The fisheye textures the room in the running game only; the editor shows the layout.
		set_process(!Engine::get_singleton()->is_editor_hint());
	}
	if (p_what == NOTIFICATION_READY) {
		connect_engine();
		take_recording_room(); // the editor too: RigCapture reads the recording's room.yaml unopened
	}
	if (p_what == NOTIFICATION_EXIT_TREE && engine && !own_engine) {
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.has_room = false; });
		engine.reset();
		pushed.clear();
	}
}

void CoarseRoomModel::_process(double p_delta) {
	(void)p_delta;
	MainThreadTimer timer(MainThreadTimer::COARSE_ROOM_MODEL);
	take_room_search();
	if (!Engine::get_singleton()->is_editor_hint()) {
		integrate_rig_frame();
	}
}

void CoarseRoomModel::take_recording_room() {
	if (floorplan_source != FLOORPLAN_RECORDING || !is_inside_tree()) {
		return;
	}
	std::string unused;
	Node *capture = find_collaborator(*this, rig_capture_path, "RigCapture", "rig_capture", &unused);
	if (capture == nullptr) {
		return;
	}
	// The RigCapture's public room (empty until it opens a recording with a room.yaml).
	const PackedVector2Array plan = capture->call("get_room_floorplan");
	const double ceiling = capture->call("get_room_ceiling_height");
	if (plan.size() < 3 || !(ceiling > 0.0) || (plan == floorplan && ceiling == ceiling_height)) {
		return;
	}
	floorplan = plan;
	ceiling_height = ceiling;
	rebuild();
}

Floorplan CoarseRoomModel::core_floorplan() const {
	Floorplan plan;
	plan.ceiling_height_m = ceiling_height;
	for (int64_t i = 0; i < floorplan.size(); i++) {
		plan.points.push_back({ floorplan[i].x, floorplan[i].y });
	}
	return plan;
}

void CoarseRoomModel::rebuild() {
	const Floorplan plan = core_floorplan();
	RoomMeshOptions options;
	options.texel_size_m = texel_size;
	check = check_floorplan(plan);
	result = build_room_mesh(plan, options);
	mesh->clear_surfaces();
	if (result.ok) {
		mesh->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, to_surface_arrays(result.mesh));
	}
	push_room();
	apply_material();
	update_configuration_warnings();
	emit_signal("mesh_changed");
}

bool CoarseRoomModel::is_valid() const { return result.ok; }
String CoarseRoomModel::get_floorplan_error() const { return String(result.error.c_str()); }
Ref<ArrayMesh> CoarseRoomModel::get_mesh() const { return mesh; }

Vector2i CoarseRoomModel::get_atlas_size() const {
	return result.ok ? Vector2i(result.mesh.atlas_width, result.mesh.atlas_height) : Vector2i();
}

bool CoarseRoomModel::set_atlas_image(const Ref<Image> &p_image) {
	ERR_FAIL_COND_V_MSG(!result.ok, false, "CoarseRoomModel.set_atlas_image: the room has no valid mesh, so no atlas.");
	ERR_FAIL_COND_V_MSG(p_image.is_null(), false, "CoarseRoomModel.set_atlas_image: no image.");
	ERR_FAIL_COND_V_MSG(p_image->get_width() != result.mesh.atlas_width || p_image->get_height() != result.mesh.atlas_height, false,
			"The image must have the atlas's size (get_atlas_size()).");
	ERR_FAIL_COND_V_MSG(p_image->is_compressed(), false, "A compressed image cannot be used as the atlas.");
	// A copy: the caller's image is left as it is.
	Ref<Image> rgb = Image::create_from_data(p_image->get_width(), p_image->get_height(), p_image->has_mipmaps(), p_image->get_format(), p_image->get_data());
	ERR_FAIL_COND_V(rgb.is_null(), false);
	if (rgb->has_mipmaps()) {
		rgb->clear_mipmaps();
	}
	rgb->convert(Image::FORMAT_RGBF);
	const PackedByteArray data = rgb->get_data();
	const int w = result.mesh.atlas_width;
	const int h = result.mesh.atlas_height;
	ERR_FAIL_COND_V(data.size() != int64_t(w) * h * 3 * int64_t(sizeof(float)), false);
	cv::Mat atlas(h, w, CV_32FC3);
	std::memcpy(atlas.data, data.ptr(), size_t(data.size()));
	if (!engine) {
		connect_engine();
	}
	engine->apply_config();
	ERR_FAIL_COND_V_MSG(!engine->set_atlas(atlas), false, String(("The engine has no room: " + engine->configuration_error()).c_str()));
	hook_atlas = atlas;
	hook_layout = pushed_layout;
	take_snapshot();
	return true;
}

Ref<Image> CoarseRoomModel::get_atlas_image() const {
	return has_texture_data() ? image_from_mat(shown->atlas) : Ref<Image>();
}

bool CoarseRoomModel::has_texture_data() const { return result.ok && shown && !shown->atlas.empty(); }

// ---------------------------------------------------------------- the engine

void CoarseRoomModel::connect_engine() {
	std::string unused; // get_warnings() reports it
	Node *capture = is_inside_tree() ? find_collaborator(*this, rig_capture_path, "RigCapture", "rig_capture", &unused) : nullptr;
	std::shared_ptr<LiveRoom> found = live_room_of(capture);
	if (found && found == engine) {
		return;
	}
	if (!found && engine && own_engine) {
		return;
	}
	if (engine && !own_engine) {
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.has_room = false; });
	}
	own_engine = !found;
	if (own_engine) {
		// No rig: the room alone, for set_atlas_image and the editor.
		found = std::make_shared<LiveRoom>();
		found->edit_config([](LiveRoomConfig &p_config) {
			p_config.has_rig = false;
			p_config.dense = false;
		});
	}
	engine = found;
	pushed.clear();
	shown.reset();
	push_room();
}

Pose CoarseRoomModel::world_from_room() const {
	Pose pose;
	if (is_inside_tree() && !pose_from_transform(get_global_transform(), &pose)) {
		return Pose(); // get_warnings() names the degenerate transform
	}
	return pose;
}

// The room and the texturing options into the engine (applied by RigCapture before the next
// frame; at once for a room-only engine). A new floorplan or pose alone, on an engine already
// running its configuration, replaces only the room (LiveRoom::set_room): the dense model and the
// tracking go on, and the texture carries over where the walls stayed.
void CoarseRoomModel::push_room() {
	if (!engine) {
		return;
	}
	const Pose placed = world_from_room();
	char key[512];
	// The atlas layout: what set_atlas_image's texture belongs to.
	std::snprintf(key, sizeof(key), "%d %.9g %.9g|", int(result.ok), ceiling_height, texel_size);
	std::string layout = key;
	for (int64_t i = 0; i < floorplan.size(); i++) {
		std::snprintf(key, sizeof(key), "%.9g,%.9g;", double(floorplan[i].x), double(floorplan[i].y));
		layout += key;
	}
	const bool find_room = floorplan_source == FLOORPLAN_AUTOMATIC;
	std::snprintf(key, sizeof(key), "%d %d %d %d|", int(inpainting), int(lighting_compensation), int(pose_source), int(find_room));
	const std::string options = key;
	// The pose to 0.1 mm and about 0.01 degrees: a node that jitters by less does not rebuild the room.
	std::snprintf(key, sizeof(key), "%.4f %.4f %.4f %.4f %.4f %.4f %.4f|", placed.translation.x, placed.translation.y, placed.translation.z, placed.rotation.w,
			placed.rotation.x, placed.rotation.y, placed.rotation.z);
	const std::string state = layout + options + key;
	pushed_layout = layout;
	if (state == pushed) {
		return; // the same room again (entering the tree, a value set twice): keep the texture
	}
	if (layout != hook_layout) {
		hook_atlas.release(); // a new layout: the texture put in no longer fits
	}
	const bool room_only = !pushed.empty() && options == pushed_options && !own_engine && engine->is_configured() && !engine->config_pending();
	pushed = state;
	pushed_options = options;
	const Floorplan plan = core_floorplan();
	if (room_only) {
		const std::string error = engine->set_room(result.ok, plan, placed, texel_size);
		if (!error.empty()) {
			ERR_PRINT(String(("CoarseRoomModel: the engine kept its old room: " + error).c_str()));
		}
		shown.reset();
		take_snapshot(); // the texture carried over, if any
		apply_material();
		return;
	}
	// The engine starts again (a new configuration): its estimates start again too.
	looked_at.reset();
	found.reset();
	engine->edit_config([&](LiveRoomConfig &p_config) {
		p_config.has_room = result.ok;
		p_config.floorplan = plan;
		p_config.world_from_room = placed;
		p_config.find_room = find_room;
		p_config.coarse.texel_size_m = texel_size;
		p_config.coarse.inpaint = inpainting;
		p_config.coarse.inpaint_async = true; // off the frame's critical path
		p_config.coarse.lighting = lighting_compensation != LIGHTING_OFF;
		p_config.coarse.lighting_model = lighting_compensation == LIGHTING_ADDITIVE ? LightingModel::ADDITIVE_PAPER : LightingModel::GAIN_ROBUST;
		p_config.coarse_poses = pose_source == POSE_SOURCE_DENSE_SLAM ? roomprobe::PoseSource::Tracked : roomprobe::PoseSource::GroundTruth;
	});
	shown.reset();
	if (own_engine) {
		engine->apply_config();
		if (!hook_atlas.empty()) {
			// Moving the room (or another option) keeps the texture set_atlas_image put in.
			engine->set_atlas(hook_atlas);
			take_snapshot();
		}
	}
	apply_material();
}

bool CoarseRoomModel::take_snapshot() {
	std::shared_ptr<const CoarseSnapshot> snapshot = engine ? engine->coarse_snapshot() : nullptr;
	if (snapshot == shown) {
		return false;
	}
	shown = snapshot;
	apply_material();
	return snapshot != nullptr;
}

bool CoarseRoomModel::integrate_rig_frame() {
	std::string unused; // get_warnings() reports it
	if (is_inside_tree() && (!engine || own_engine) && find_collaborator(*this, rig_capture_path, "RigCapture", "rig_capture", &unused) != nullptr) {
		connect_engine(); // the RigCapture may have come later
	}
	take_recording_room();
	take_found_room();
	push_room(); // the node moved or turned: the room follows (nothing to do otherwise)
	const uint64_t before = shown ? shown->frames : 0;
	if (!take_snapshot() || shown->frames == before || shown->frames == 0) {
		return false;
	}
	emit_signal("texture_updated", int64_t(shown->frames - 1));
	return true;
}

int64_t CoarseRoomModel::get_integrated_frame_count() const { return shown ? int64_t(shown->frames) : 0; }

Dictionary CoarseRoomModel::get_last_frame_stats() const {
	Dictionary d;
	if (!shown || shown->frames == 0) {
		return d;
	}
	const CoarseFrameStats &last = shown->last;
	const CoarsePipelineTimings &t = shown->timings;
	d.set("texels_visible", int64_t(last.update.texels_visible));
	d.set("texels_updated", int64_t(last.update.texels_updated));
	d.set("occlusion_skipped", last.occlusion_skipped);
	d.set("lighting_valid", last.lighting.valid);
	d.set("lighting_gain", Vector3(last.lighting.gain[0], last.lighting.gain[1], last.lighting.gain[2]));
	d.set("lighting_offset", Vector3(last.lighting.offset[0], last.lighting.offset[1], last.lighting.offset[2]));
	d.set("occlusion_ms", t.occlusion_ms);
	d.set("lighting_ms", t.lighting_ms);
	d.set("update_ms", t.update_ms);
	d.set("inpaint_ms", t.inpaint_ms);
	d.set("frame_ms", t.frame_ms);
	return d;
}

void CoarseRoomModel::reset_texture() {
	if (engine) {
		// The engine starts its models again: every observation is forgotten.
		engine->edit_config([](LiveRoomConfig &) {});
		engine->apply_config();
	}
	shown.reset();
	apply_material();
}

void CoarseRoomModel::finish_inpainting() {
	if (engine) {
		engine->finish();
		take_snapshot();
	}
}

Error CoarseRoomModel::save_room(const String &p_path, bool p_overwrite) {
	ERR_FAIL_COND_V_MSG(!result.ok, ERR_UNCONFIGURED, String(("save_room: the room is not valid, so not saved: " + result.error).c_str()));
	std::string error;
	const std::string path = disk_path_for(p_path, &error);
	ERR_FAIL_COND_V_MSG(!error.empty(), ERR_FILE_BAD_PATH, String(("save_room: " + error).c_str()));
	std::error_code ec;
	ERR_FAIL_COND_V_MSG(!p_overwrite && std::filesystem::exists(path, ec), ERR_ALREADY_EXISTS,
			String(("save_room: " + path + " exists and is kept; pass overwrite = true to replace it").c_str()));
	RoomInfo room;
	room.floorplan = core_floorplan();
	const Pose room_from_world = inverse(world_from_room());
	if (engine && !own_engine) {
		const Trajectory path_taken = engine->trajectory();
		room.initial_rgb_pose = compose(room_from_world, path_taken.get_samples().empty() ? engine->config().initial_rgb_pose
																						  : path_taken.get_samples().front().world_from_camera);
		for (const glm::dvec3 &probe : engine->probe_positions()) {
			room.probes.push_back(transform_point(room_from_world, probe));
		}
	}
	error = save_room_file(path, room);
	ERR_FAIL_COND_V_MSG(!error.empty(), ERR_FILE_CANT_WRITE, String(("save_room: " + error).c_str()));
	return OK;
}

Array CoarseRoomModel::get_charts() const {
	Array charts;
	if (!result.ok) {
		return charts;
	}
	for (const Chart &c : result.mesh.charts) {
		Dictionary d;
		d.set("kind", String(c.kind == SurfaceKind::Wall ? "wall" : c.kind == SurfaceKind::Floor ? "floor" : "ceiling"));
		d.set("rect", Rect2i(c.x, c.y, c.w, c.h));
		d.set("normal", Vector3(real_t(c.normal.x), real_t(c.normal.y), real_t(c.normal.z)));
		d.set("wall_index", c.wall_index);
		charts.push_back(d);
	}
	return charts;
}

// Shows the atlas on the mesh (unshaded: the atlas already holds the room's light) while
// there is texture data; the plain mesh otherwise.
void CoarseRoomModel::apply_material() {
	if (mesh_instance == nullptr) {
		return;
	}
	if (!has_texture_data()) {
		mesh_instance->set_material_override(Ref<Material>());
		return;
	}
	show_in_texture(image_from_buffer(shown->display), atlas_texture);
	if (material.is_null()) {
		material.instantiate();
		material->set_shading_mode(BaseMaterial3D::SHADING_MODE_UNSHADED);
	}
	material->set_texture(BaseMaterial3D::TEXTURE_ALBEDO, atlas_texture);
	mesh_instance->set_material_override(material);
}

PackedStringArray CoarseRoomModel::get_warnings() const {
	PackedStringArray warnings;
	if (!result.ok) {
		// A valid floorplan can still fail to build (e.g. an atlas beyond the size limit).
		const char *phrase = check.ok ? "The room cannot be built" : floorplan_problem_summary(check.problem);
		warnings.push_back(String((std::string(phrase) + ": " + result.error).c_str()));
	}
	if (is_inside_tree()) {
		Pose unused_pose;
		const glm::dmat3 axes = to_glm(get_global_transform().basis); // columns: the axes, their lengths the scale
		const auto unscaled = [](const glm::dvec3 &p_axis) { return std::abs(glm::length(p_axis) - 1.0) <= 1e-3; };
		if (!pose_from_transform(get_global_transform(), &unused_pose)) {
			warnings.push_back("The node's transform is degenerate or mirrored: the room is placed at the world's origin instead.");
		} else if (!unscaled(axes[0]) || !unscaled(axes[1]) || !unscaled(axes[2])) {
			warnings.push_back("The node is scaled: the room is in metres, so the maps and placement ignore the scale while the mesh shows it.");
		}
	}
	if (floorplan_source == FLOORPLAN_AUTOMATIC && engine && !own_engine) {
		const std::shared_ptr<const FoundRoom> newest = engine->found_room();
		if (newest && !newest->result.has_room) {
			warnings.push_back(String(("No room found yet (" + std::string(room_estimate_state_name(newest->result.estimate.state)) + "): " +
					newest->result.estimate.message).c_str()));
		}
		for (int64_t i = 0; i < wall_confidence.size(); i++) {
			if (wall_confidence[i] < 0.3f) {
				warnings.push_back(String(("Edge " + std::to_string(i) + " of the room found was never seen as a wall: the room ends there where the sweep's view did.").c_str()));
			}
		}
	} else if (floorplan_source == FLOORPLAN_AUTOMATIC && is_inside_tree()) {
		warnings.push_back("floorplan_source is Automatic, but there is no RigCapture: the room is found from a sweep's dense model (RigCapture and DenseSLAM).");
	}
	std::string warning;
	const Node *capture = is_inside_tree() ? find_collaborator(*this, rig_capture_path, "RigCapture", "rig_capture", &warning) : nullptr;
	if (!warning.empty()) {
		warnings.push_back(String(warning.c_str()));
	}
	if (is_inside_tree() && pose_source == POSE_SOURCE_DENSE_SLAM && capture != nullptr) {
		std::string slam_warning;
		if (find_collaborator(*this, dense_slam_path, "DenseSLAM", "dense_slam", &slam_warning) == nullptr) {
			warnings.push_back(String(("Fisheye frames are not being integrated: pose_source is Dense SLAM, but there is no DenseSLAM. " + slam_warning).c_str()));
		}
	}
	if (engine && !own_engine && !engine->config_pending()) {
		const std::string error = engine->configuration_error();
		const LiveRoomStats stats = engine->stats();
		if (!error.empty()) {
			warnings.push_back(String(("Fisheye frames are not being integrated: " + error + ".").c_str()));
		} else if (stats.fisheye_integrated == 0 && stats.fisheye_without_pose > 0) {
			warnings.push_back(String(("Fisheye frames are not being integrated: " + stats.fisheye_pose_problem + ".").c_str()));
		}
	}
	return warnings;
}

} // namespace roomprobe
