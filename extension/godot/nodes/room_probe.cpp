#include "room_probe.h"

#include "../property_checks.h"

#include "../convert/image_convert.h"
#include "../convert/pose_convert.h"

#include <glm/matrix.hpp>
#include "../convert/virtual_object_convert.h"

#include <envmap/export.h>
#include <envmap/spherical_harmonics.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <limits>

using namespace godot;

namespace roomprobe {

namespace {

// Route (c): the probe's cubemap as the sky. EYEDIR is a world direction, sampled with the same
// convention as shaders/mirror.gdshader. Godot prefilters the sky into its radiance maps itself
// (GGX), so StandardMaterial3D roughness works with no custom shader.
const char *const SKY_SHADER_CODE = R"(shader_type sky;
uniform samplerCube environment : hint_default_black, filter_linear_mipmap;
uniform float energy = 1.0;
void sky() {
	COLOR = energy * texture(environment, EYEDIR).rgb;
}
)";

std::string global_path(const String &p_path) {
	return ProjectSettings::get_singleton()->globalize_path(p_path).utf8_string();
}

} // namespace

RoomProbe::RoomProbe() = default;

RoomProbe::~RoomProbe() {
	disconnect_engine();
}

void RoomProbe::set_resolution(int64_t p_texels) {
	resolution = int(property_checks::clamped_int("RoomProbe.resolution", p_texels, RESOLUTION_MIN, RESOLUTION_MAX, " texels"));
	if (engine && probe_id != 0) {
		place_in_engine();
	}
}

int RoomProbe::get_resolution() const { return resolution; }

void RoomProbe::set_coarse_model_path(const NodePath &p_path) {
	coarse_model_path = p_path;
	if (is_inside_tree()) {
		connect_engine();
	}
	update_configuration_warnings();
}

NodePath RoomProbe::get_coarse_model_path() const { return coarse_model_path; }
void RoomProbe::set_dense_slam_path(const NodePath &p_path) {
	dense_slam_path = p_path;
	update_configuration_warnings();
}
NodePath RoomProbe::get_dense_slam_path() const { return dense_slam_path; }

void RoomProbe::set_update_mode(int64_t p_mode) {
	if (!property_checks::enum_in_range("RoomProbe.update_mode", p_mode, 2)) {
		return;
	}
	update_mode = UpdateMode(p_mode);
}

RoomProbe::UpdateMode RoomProbe::get_update_mode() const { return update_mode; }

void RoomProbe::set_target_material(const Ref<Material> &p_material) {
	const Ref<ShaderMaterial> shader_material(p_material); // null unless it is one
	if (p_material.is_valid() && shader_material.is_null()) {
		// Issue #38: it used to become null without a word.
		ERR_PRINT(String(("RoomProbe.target_material: a " + p_material->get_class().utf8_string() +
				" cannot read the map: give a ShaderMaterial whose shader has the cubemap uniform (shaders/mirror.gdshader, "
				"rough_metal.gdshader, ...), or set reflection_probe or world_environment for a StandardMaterial3D; kept as it was")
								  .c_str()));
		return;
	}
	restore_driven(); // the old material (and the other outputs, driven again below) as they were
	target_material = shader_material;
	drive_outputs();
}

Ref<ShaderMaterial> RoomProbe::get_target_material() const { return target_material; }

void RoomProbe::set_material_parameter(const StringName &p_name) {
	material_parameter = p_name;
	apply_to_material();
}

StringName RoomProbe::get_material_parameter() const { return material_parameter; }

void RoomProbe::set_sh_parameter(const StringName &p_name) {
	sh_parameter = p_name;
	apply_to_material();
}

StringName RoomProbe::get_sh_parameter() const { return sh_parameter; }

void RoomProbe::set_position_parameter(const StringName &p_name) {
	position_parameter = p_name;
	apply_to_material();
}

StringName RoomProbe::get_position_parameter() const { return position_parameter; }

void RoomProbe::set_reflection_probe_path(const NodePath &p_path) {
	restore_driven();
	reflection_probe_path = p_path;
	if (is_inside_tree()) {
		drive_outputs();
	}
	update_configuration_warnings();
}

NodePath RoomProbe::get_reflection_probe_path() const { return reflection_probe_path; }

void RoomProbe::set_world_environment_path(const NodePath &p_path) {
	restore_driven();
	world_environment_path = p_path;
	if (is_inside_tree()) {
		drive_outputs();
	}
	update_configuration_warnings();
}

NodePath RoomProbe::get_world_environment_path() const { return world_environment_path; }

void RoomProbe::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY) {
		connect_engine();
		// A first map at once when the room is there; quietly none otherwise (see the warnings):
		// _process renders it once the room exists, in either update mode.
		if (engine && engine->room_mesh() != nullptr && update_now()) {
			once_room_version = engine->room_version();
		}
		set_process(true);
	} else if (p_what == NOTIFICATION_EXIT_TREE) {
		restore_driven(); // the user's nodes as they were (a closed tab, a deleted probe)
		disconnect_engine();
	} else if (p_what == NOTIFICATION_EDITOR_PRE_SAVE) {
		restore_driven(); // the scene is saved with the user's own values
	} else if (p_what == NOTIFICATION_EDITOR_POST_SAVE) {
		drive_outputs();
	}
}

void RoomProbe::remember_original(const Object *p_target, const StringName &p_property, bool p_shader_parameter, const Variant &p_current) {
	const uint64_t id = p_target->get_instance_id();
	const bool known = std::any_of(driven.begin(), driven.end(),
			[&](const Driven &p_d) { return p_d.object == id && p_d.shader_parameter == p_shader_parameter && p_d.property == p_property; });
	if (!known) {
		driven.push_back({ id, p_property, p_shader_parameter, p_current });
	}
}

void RoomProbe::drive(Object *p_target, const StringName &p_property, const Variant &p_value) {
	remember_original(p_target, p_property, false, p_target->get(p_property));
	p_target->set(p_property, p_value);
}

void RoomProbe::drive_shader_parameter(const Ref<ShaderMaterial> &p_material, const StringName &p_name, const Variant &p_value) {
	remember_original(p_material.ptr(), p_name, true, p_material->get_shader_parameter(p_name));
	p_material->set_shader_parameter(p_name, p_value);
}

void RoomProbe::restore_driven() {
	// Newest first, so a property driven twice ends at its first value.
	for (auto it = driven.rbegin(); it != driven.rend(); ++it) {
		Object *target = UtilityFunctions::instance_from_id(int64_t(it->object));
		if (target == nullptr) {
			continue;
		}
		if (it->shader_parameter) {
			ShaderMaterial *material = cast_to<ShaderMaterial>(target);
			if (material != nullptr) {
				material->set_shader_parameter(it->property, it->original);
			}
		} else {
			target->set(it->property, it->original);
		}
	}
	driven.clear();
}

void RoomProbe::drive_outputs() {
	if (!map) {
		return;
	}
	apply_to_material();
	drive_reflection_probe();
	drive_world_environment();
}

void RoomProbe::_process(double p_delta) {
	(void)p_delta;
	MainThreadTimer timer(MainThreadTimer::ROOM_PROBE);
	if (!engine) {
		connect_engine();
		if (!engine) {
			return;
		}
	}
	if (update_mode == UPDATE_ONCE) {
		process_once();
		return;
	}
	if (engine->is_running()) {
		// The probe worker renders; this only says where the probe is and takes finished maps.
		place_in_engine();
		refresh_virtual_objects();
		if (take_map()) {
			emit_signal("environment_map_updated");
		}
	} else if (!engine->config_pending() && engine->room_mesh() != nullptr) {
		if (Engine::get_singleton()->is_editor_hint()) {
			// The editor: only when the probe moved, or its room, objects or size changed (an idle
			// scene costs nothing).
			place_in_engine();
			refresh_virtual_objects();
			if (engine->probe_is_current(probe_id)) {
				return;
			}
		}
		update_now(); // step mode: rendered here, as the frames are
	}
}

void RoomProbe::connect_engine() {
	std::string warning;
	Node *room = is_inside_tree() ? find_collaborator(*this, coarse_model_path, "CoarseRoomModel", "coarse_model", &warning) : nullptr;
	std::shared_ptr<LiveRoom> found = live_room_of(room);
	if (found == engine) {
		return;
	}
	disconnect_engine();
	engine = found;
	if (engine) {
		probe_id = engine->add_probe(to_glm(get_global_position()), resolution);
	}
}

void RoomProbe::disconnect_engine() {
	if (engine && probe_id != 0) {
		engine->remove_probe(probe_id);
	}
	engine.reset();
	probe_id = 0;
}

// Tells the engine where the probe is; a probe far outside the room sees it from behind its walls
// (a map of nothing), which is said once each time it leaves.
void RoomProbe::place_in_engine() {
	const glm::dvec3 position = to_glm(get_global_position());
	engine->set_probe(probe_id, position, resolution);
	const double outside_m = engine->distance_outside_room_m(position);
	const bool outside = outside_m > PROBE_OUTSIDE_WARNING_M;
	if (outside && !outside_room) {
		char text[192];
		std::snprintf(text, sizeof(text), "RoomProbe %s is %.2f m outside the room: its map sees the room from outside, mostly empty.",
				String(get_name()).utf8_string().c_str(), outside_m);
		WARN_PRINT(text);
	}
	if (outside != outside_room) {
		outside_room = outside;
		outside_room_m = outside_m;
		update_configuration_warnings();
	}
}

// Once: one map per room, as soon as the room exists (a recording's room comes after ready, a
// room found from the sweep later still), then nothing until the next room.
void RoomProbe::process_once() {
	const uint64_t room = engine->room_version();
	if (room == once_room_version || engine->config_pending() || engine->room_mesh() == nullptr) {
		return;
	}
	if (!engine->is_running()) {
		if (update_now()) {
			once_room_version = room;
		}
		return;
	}
	// Live: the probe worker renders it; the first map it finishes for this room is the one.
	place_in_engine();
	refresh_virtual_objects();
	if (take_map()) {
		once_room_version = room;
		emit_signal("environment_map_updated");
	}
}

bool RoomProbe::update_now() {
	MainThreadTimer timer(MainThreadTimer::ROOM_PROBE);
	if (!engine) {
		connect_engine();
	}
	ERR_FAIL_COND_V_MSG(!engine, false, "coarse_model does not lead to a CoarseRoomModel in the tree.");
	if (engine->config_pending()) {
		engine->apply_config();
	}
	ERR_FAIL_COND_V_MSG(engine->room_mesh() == nullptr, false, "The CoarseRoomModel has no valid room.");
	place_in_engine();
	refresh_virtual_objects();
	ERR_FAIL_COND_V_MSG(!engine->render_probe(probe_id), false, "Rendering the probe's map failed.");
	take_map();
	emit_signal("environment_map_updated");
	return true;
}

bool RoomProbe::take_map() {
	const std::shared_ptr<const ProbeMap> newest = engine ? engine->probe_map(probe_id) : nullptr;
	if (!newest || newest == map || !is_valid_cubemap(newest->cubemap)) {
		return false;
	}
	const auto start = std::chrono::steady_clock::now();
	const int size = newest->cubemap.size;
	const bool same_size = cubemap.is_valid() && cubemap->get_width() == size && cubemap->get_layers() == 6;
	Array layers;
	for (int i = 0; i < 6; i++) {
		if (same_size && map && map->gpu_faces[size_t(i)] == newest->gpu_faces[size_t(i)]) {
			continue; // the engine kept the previous map's face: nothing to upload
		}
		// The worker built the half floats and their mips in Godot's own array: nothing is copied here.
		Ref<Image> gpu = Image::create_from_data(size, size, true, Image::FORMAT_RGBAH, packed_bytes(*newest->gpu_faces[size_t(i)]));
		ERR_FAIL_COND_V(gpu.is_null(), false);
		if (same_size) {
			cubemap->update_layer(gpu, i);
		} else {
			layers.push_back(gpu);
		}
		faces[i].unref();
	}
	if (!same_size) {
		cubemap.instantiate();
		const Error err = cubemap->create_from_images(layers);
		ERR_FAIL_COND_V_MSG(err != OK, false, "Could not create the Cubemap.");
	}
	map = newest;
	apply_to_material();
	drive_reflection_probe();
	drive_world_environment();
	upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	return true;
}

Dictionary RoomProbe::get_last_update_stats() const {
	Dictionary d;
	if (!map) {
		return d;
	}
	d.set("dense_texels", int64_t(map->dense.texels_covered));
	d.set("dense_ms", map->dense_ms);
	d.set("coarse_ms", map->coarse_ms);
	d.set("render_ms", map->total_ms);
	d.set("upload_ms", upload_ms);
	d.set("update_ms", map->total_ms + upload_ms);
	d.set("mips_ms", map->mips_ms);
	d.set("ggx_mips", map->ggx_mips);
	d.set("objects_ms", map->objects.milliseconds);
	d.set("objects_texels_traced", int64_t(map->objects.texels_traced));
	d.set("objects_texels_drawn", int64_t(map->objects.texels_drawn + map->objects.texels_shadowed));
	return d;
}

void RoomProbe::drive_reflection_probe() {
	if (reflection_probe_path.is_empty() || !engine) {
		return;
	}
	ReflectionProbe *probe = cast_to<ReflectionProbe>(get_node_or_null(reflection_probe_path));
	ERR_FAIL_NULL_MSG(probe, "reflection_probe does not lead to a ReflectionProbe.");
	const RoomMesh *mesh = engine->room_mesh();
	if (mesh == nullptr) {
		return; // no room yet (an Automatic one not found so far): the ReflectionProbe stays as set
	}
	std::string warning;
	const Node3D *room = cast_to<Node3D>(find_collaborator(*this, coarse_model_path, "CoarseRoomModel", "coarse_model", &warning));
	ERR_FAIL_NULL(room);
	// The room's box, for box projection: reflections of the walls then move with the viewer
	// (parallax) instead of sitting at infinity. The box is the room's, turned as the room is (a
	// room found from the sweep is turned in the world).
	Vector3 lo(std::numeric_limits<real_t>::max(), std::numeric_limits<real_t>::max(), std::numeric_limits<real_t>::max());
	Vector3 hi = -lo;
	for (const Vec3f &v : mesh->positions) {
		lo = Vector3(std::min(lo.x, real_t(v.x)), std::min(lo.y, real_t(v.y)), std::min(lo.z, real_t(v.z)));
		hi = Vector3(std::max(hi.x, real_t(v.x)), std::max(hi.y, real_t(v.y)), std::max(hi.z, real_t(v.z)));
	}
	Pose world_from_room;
	if (!pose_from_transform(room->get_global_transform(), &world_from_room)) {
		world_from_room = Pose();
	}
	Pose world_from_box = world_from_room;
	world_from_box.translation = transform_point(world_from_room, to_glm((lo + hi) * 0.5));
	// Its local transform (a global one cannot be put back once the probe has left the tree).
	Transform3D box = transform_from_pose(world_from_box);
	const Node3D *parent = cast_to<Node3D>(probe->get_parent());
	if (parent != nullptr) { // in the parent's space, its scale included
		const glm::dmat3 parent_axes = to_glm(parent->get_global_transform().basis);
		if (std::abs(glm::determinant(parent_axes)) > 1e-12) {
			box.basis = to_godot(glm::inverse(parent_axes) * to_glm(box.basis));
			box.origin = parent->to_local(box.origin);
		}
	}
	drive(probe, "transform", box);
	drive(probe, "size", hi - lo);
	drive(probe, "origin_offset", to_godot(transform_point(inverse(world_from_box), to_glm(get_global_position()))));
	drive(probe, "box_projection", true);
	drive(probe, "interior", true);
	// Only the textured room: not the virtual objects, nor the rest of the scene.
	drive(probe, "cull_mask", int64_t(const_cast<Node3D *>(room)->get("room_layers")));
	// In the editor a map comes only when something changed: the ReflectionProbe need not re-render
	// every frame either (an idle editor stays idle).
	const bool every_frame = update_mode == UPDATE_ALWAYS && !Engine::get_singleton()->is_editor_hint();
	drive(probe, "update_mode", int64_t(every_frame ? ReflectionProbe::UPDATE_ALWAYS : ReflectionProbe::UPDATE_ONCE));
}

void RoomProbe::drive_world_environment() {
	if (world_environment_path.is_empty()) {
		return;
	}
	WorldEnvironment *world = cast_to<WorldEnvironment>(get_node_or_null(world_environment_path));
	ERR_FAIL_NULL_MSG(world, "world_environment does not lead to a WorldEnvironment.");
	Ref<Environment> environment = world->get_environment();
	if (environment.is_null()) {
		Ref<Environment> made;
		made.instantiate();
		drive(world, "environment", made);
		environment = made;
	}
	if (sky_material.is_null()) {
		Ref<Shader> shader;
		shader.instantiate();
		shader->set_code(SKY_SHADER_CODE);
		sky_material.instantiate();
		sky_material->set_shader(shader);
		sky.instantiate();
		sky->set_material(sky_material);
	}
	// A live map changes every frame: only REALTIME re-filters the radiance every frame.
	sky->set_process_mode(update_mode == UPDATE_ALWAYS && !Engine::get_singleton()->is_editor_hint() ? Sky::PROCESS_MODE_REALTIME : Sky::PROCESS_MODE_AUTOMATIC);
	sky_material->set_shader_parameter("environment", cubemap);
	if (environment->get_sky() != sky) {
		drive(environment.ptr(), "sky", sky);
	}
	// The background stays as the scene has it (an AR app shows the camera image there).
	drive(environment.ptr(), "reflected_light_source", int64_t(Environment::REFLECTION_SOURCE_SKY));
	drive(environment.ptr(), "ambient_light_source", int64_t(Environment::AMBIENT_SOURCE_SKY));
}

Ref<ShaderMaterial> RoomProbe::get_sky_material() const { return sky_material; }

Error RoomProbe::save_exr(const String &p_path) const {
	ERR_FAIL_COND_V_MSG(!map, ERR_UNAVAILABLE, "RoomProbe.save_exr: no environment map yet: call update_now() first.");
	const std::string error = write_cubemap_exr(global_path(p_path), map->cubemap);
	ERR_FAIL_COND_V_MSG(!error.empty(), ERR_FILE_CANT_WRITE, String(error.c_str()));
	return OK;
}

Error RoomProbe::save_png_net(const String &p_path) const {
	ERR_FAIL_COND_V_MSG(!map, ERR_UNAVAILABLE, "RoomProbe.save_png_net: no environment map yet: call update_now() first.");
	const std::string error = write_cubemap_png_net(global_path(p_path), map->cubemap);
	ERR_FAIL_COND_V_MSG(!error.empty(), ERR_FILE_CANT_WRITE, String(error.c_str()));
	return OK;
}

Ref<Image> RoomProbe::get_net_image() const {
	return map ? image_from_mat(cubemap_net_image(map->cubemap)) : Ref<Image>();
}

void RoomProbe::apply_to_material() {
	if (target_material.is_null() || !map) {
		return;
	}
	if (!String(material_parameter).is_empty()) {
		drive_shader_parameter(target_material, material_parameter, cubemap);
	}
	if (!String(position_parameter).is_empty()) {
		drive_shader_parameter(target_material, position_parameter, to_godot(map->position)); // where the map was rendered
	}
	if (!String(sh_parameter).is_empty()) {
		Node3D *frame = sh_frame_path.is_empty() || !is_inside_tree() ? nullptr : cast_to<Node3D>(get_node_or_null(sh_frame_path));
		drive_shader_parameter(target_material, sh_parameter, frame ? get_sh_coefficients_in(frame->get_global_basis()) : get_sh_coefficients());
	}
}

void RoomProbe::set_sh_frame_path(const NodePath &p_path) {
	sh_frame_path = p_path;
	apply_to_material();
	update_configuration_warnings();
}

NodePath RoomProbe::get_sh_frame_path() const { return sh_frame_path; }

void RoomProbe::set_virtual_objects_mask(int64_t p_mask) {
	virtual_objects_mask = property_checks::render_layers("RoomProbe.virtual_objects_mask", p_mask);
	virtual_objects_signature.clear();
	if (virtual_objects_mask == 0 && engine && probe_id != 0) {
		engine->set_probe_objects(probe_id, nullptr);
		virtual_object_count = 0;
	}
}

uint32_t RoomProbe::get_virtual_objects_mask() const { return virtual_objects_mask; }

int RoomProbe::get_virtual_object_count() const { return virtual_object_count; }

namespace {

void collect_instances(Node *p_node, const Viewport *p_viewport, uint32_t p_mask, std::vector<MeshInstance3D *> *r_found) {
	MeshInstance3D *instance = cast_to<MeshInstance3D>(p_node);
	if (instance != nullptr && (instance->get_layer_mask() & p_mask) != 0 && instance->is_visible_in_tree() && instance->get_viewport() == p_viewport) {
		r_found->push_back(instance);
	}
	for (int i = 0; i < p_node->get_child_count(); i++) {
		collect_instances(p_node->get_child(i), p_viewport, p_mask, r_found);
	}
}

} // namespace

void RoomProbe::refresh_virtual_objects() {
	if (virtual_objects_mask == 0 || !engine || probe_id == 0 || !is_inside_tree()) {
		return;
	}
	Viewport *viewport = get_viewport();
	std::vector<MeshInstance3D *> found;
	collect_instances(viewport, viewport, virtual_objects_mask, &found);
	// The probe's own object is never drawn: its parent, its sh_frame, whatever wears target_material.
	const Node *own_frame = sh_frame_path.is_empty() ? nullptr : get_node_or_null(sh_frame_path);
	std::erase_if(found, [&](MeshInstance3D *p_instance) {
		return p_instance == get_parent() || p_instance == own_frame ||
				(target_material.is_valid() && p_instance->get_material_override() == Ref<Material>(target_material));
	});
	// Only a change (an object, its mesh, material or transform) rebuilds the scene.
	std::vector<VirtualObjectKey> signature;
	for (MeshInstance3D *instance : found) {
		signature.push_back({ instance->get_instance_id(), instance->get_mesh().ptr(), instance->get_material_override().ptr(), instance->get_global_transform() });
	}
	if (signature == virtual_objects_signature) {
		return;
	}
	virtual_objects_signature = signature;
	std::vector<VirtualObject> objects;
	for (MeshInstance3D *instance : found) {
		VirtualObject object;
		const std::string error = virtual_object_from_instance(instance, &object);
		if (!error.empty()) {
			WARN_PRINT(String(("RoomProbe: virtual object " + std::string(String(instance->get_name()).utf8_string()) + " left out: " + error).c_str()));
			continue;
		}
		objects.push_back(std::move(object));
	}
	std::shared_ptr<const VirtualScene> scene;
	const std::string error = VirtualScene::make(std::move(objects), &scene);
	ERR_FAIL_COND_MSG(!error.empty(), String(("RoomProbe: " + error).c_str()));
	virtual_object_count = int(scene->object_count());
	engine->set_probe_objects(probe_id, scene);
}

Ref<godot::Cubemap> RoomProbe::get_cubemap() const { return cubemap; }

Ref<Image> RoomProbe::get_face_image(int p_layer) const {
	ERR_FAIL_COND_V_MSG(p_layer < 0 || p_layer >= 6, Ref<Image>(), String("RoomProbe.get_face_image: layer must be a cubemap face, 0..5; got ") + String::num_int64(p_layer));
	if (faces[p_layer].is_null() && map) {
		faces[p_layer] = image_from_mat(map->cubemap.faces[size_t(p_layer)]);
	}
	return faces[p_layer];
}

namespace {

PackedVector3Array packed_sh(const ShCoefficients &p_sh) {
	PackedVector3Array out;
	out.resize(SH_COEFFICIENTS);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		out[i] = to_godot(p_sh[size_t(i)]);
	}
	return out;
}

} // namespace

PackedVector3Array RoomProbe::get_sh_coefficients() const {
	return map ? packed_sh(map->sh) : PackedVector3Array();
}

PackedVector3Array RoomProbe::get_sh_coefficients_in(const Basis &p_basis) const {
	if (!map) {
		return PackedVector3Array();
	}
	glm::dmat3 rotation;
	ERR_FAIL_COND_V_MSG(!rotation_from_basis(p_basis, &rotation), PackedVector3Array(), "get_sh_coefficients_in: the basis is degenerate or not finite.");
	return packed_sh(rotate_sh(map->sh, rotation));
}

PackedStringArray RoomProbe::get_warnings() const {
	PackedStringArray warnings;
	if (!is_inside_tree()) {
		warnings.push_back("Not in a scene: it renders the room of the CoarseRoomModel of its scene (or the one coarse_model leads to).");
	} else {
		std::string warning;
		const Node *room = find_collaborator(*this, coarse_model_path, "CoarseRoomModel", "coarse_model", &warning);
		if (!warning.empty()) {
			warnings.push_back(String(warning.c_str()));
		} else if (room == nullptr) {
			warnings.push_back("No CoarseRoomModel in the scene: add one, or set coarse_model to it.");
		} else if (!bool(const_cast<Node *>(room)->call("is_valid"))) {
			warnings.push_back("The CoarseRoomModel has no valid room: no environment map.");
		}
	}
	if (outside_room) {
		char text[160];
		std::snprintf(text, sizeof(text), "The probe is %.2f m outside the room (floorplan and ceiling): its map sees the room from outside.", outside_room_m);
		warnings.push_back(text);
	}
	if (is_inside_tree() && !reflection_probe_path.is_empty() && cast_to<ReflectionProbe>(get_node_or_null(reflection_probe_path)) == nullptr) {
		warnings.push_back("reflection_probe does not lead to a ReflectionProbe.");
	}
	if (is_inside_tree() && !world_environment_path.is_empty() && cast_to<WorldEnvironment>(get_node_or_null(world_environment_path)) == nullptr) {
		warnings.push_back("world_environment does not lead to a WorldEnvironment.");
	}
	if (target_material.is_null() && reflection_probe_path.is_empty() && world_environment_path.is_empty()) {
		warnings.push_back("The map reaches nothing: set target_material, reflection_probe or world_environment (or read get_cubemap() from a script).");
	}
	if (!dense_slam_path.is_empty() && is_inside_tree()) {
		const Node *slam = get_node_or_null(dense_slam_path);
		if (slam == nullptr || !slam->is_class("DenseSLAM")) {
			warnings.push_back("dense_slam does not lead to a DenseSLAM node.");
		}
	}
	return warnings;
}

void RoomProbe::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &RoomProbe::get_warnings);
	ClassDB::bind_method(D_METHOD("set_resolution", "texels"), &RoomProbe::set_resolution);
	ClassDB::bind_method(D_METHOD("get_resolution"), &RoomProbe::get_resolution);
	ClassDB::bind_method(D_METHOD("set_coarse_model", "path"), &RoomProbe::set_coarse_model_path);
	ClassDB::bind_method(D_METHOD("get_coarse_model"), &RoomProbe::get_coarse_model_path);
	ClassDB::bind_method(D_METHOD("set_dense_slam", "path"), &RoomProbe::set_dense_slam_path);
	ClassDB::bind_method(D_METHOD("get_dense_slam"), &RoomProbe::get_dense_slam_path);
	ClassDB::bind_method(D_METHOD("set_update_mode", "mode"), &RoomProbe::set_update_mode);
	ClassDB::bind_method(D_METHOD("get_update_mode"), &RoomProbe::get_update_mode);
	ClassDB::bind_method(D_METHOD("set_target_material", "material"), &RoomProbe::set_target_material);
	ClassDB::bind_method(D_METHOD("get_target_material"), &RoomProbe::get_target_material);
	ClassDB::bind_method(D_METHOD("set_material_parameter", "name"), &RoomProbe::set_material_parameter);
	ClassDB::bind_method(D_METHOD("get_material_parameter"), &RoomProbe::get_material_parameter);
	ClassDB::bind_method(D_METHOD("set_sh_parameter", "name"), &RoomProbe::set_sh_parameter);
	ClassDB::bind_method(D_METHOD("get_sh_parameter"), &RoomProbe::get_sh_parameter);
	ClassDB::bind_method(D_METHOD("set_position_parameter", "name"), &RoomProbe::set_position_parameter);
	ClassDB::bind_method(D_METHOD("get_position_parameter"), &RoomProbe::get_position_parameter);
	ClassDB::bind_method(D_METHOD("update_now"), &RoomProbe::update_now);
	ClassDB::bind_method(D_METHOD("get_cubemap"), &RoomProbe::get_cubemap);
	ClassDB::bind_method(D_METHOD("get_face_image", "layer"), &RoomProbe::get_face_image);
	ClassDB::bind_method(D_METHOD("get_sh_coefficients"), &RoomProbe::get_sh_coefficients);
	ClassDB::bind_method(D_METHOD("get_sh_coefficients_in", "basis"), &RoomProbe::get_sh_coefficients_in);
	ClassDB::bind_method(D_METHOD("set_virtual_objects_mask", "mask"), &RoomProbe::set_virtual_objects_mask);
	ClassDB::bind_method(D_METHOD("get_virtual_objects_mask"), &RoomProbe::get_virtual_objects_mask);
	ClassDB::bind_method(D_METHOD("get_virtual_object_count"), &RoomProbe::get_virtual_object_count);
	ClassDB::bind_method(D_METHOD("set_sh_frame", "path"), &RoomProbe::set_sh_frame_path);
	ClassDB::bind_method(D_METHOD("get_sh_frame"), &RoomProbe::get_sh_frame_path);
	ClassDB::bind_method(D_METHOD("get_last_update_stats"), &RoomProbe::get_last_update_stats);
	ClassDB::bind_method(D_METHOD("save_exr", "path"), &RoomProbe::save_exr);
	ClassDB::bind_method(D_METHOD("save_png_net", "path"), &RoomProbe::save_png_net);
	ClassDB::bind_method(D_METHOD("get_net_image"), &RoomProbe::get_net_image);
	ClassDB::bind_method(D_METHOD("get_sky_material"), &RoomProbe::get_sky_material);
	ClassDB::bind_method(D_METHOD("set_reflection_probe", "path"), &RoomProbe::set_reflection_probe_path);
	ClassDB::bind_method(D_METHOD("get_reflection_probe"), &RoomProbe::get_reflection_probe_path);
	ClassDB::bind_method(D_METHOD("set_world_environment", "path"), &RoomProbe::set_world_environment_path);
	ClassDB::bind_method(D_METHOD("get_world_environment"), &RoomProbe::get_world_environment_path);

	ADD_GROUP("Map", "");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "resolution", PROPERTY_HINT_ENUM, "64:64,128:128,256:256,512:512"), "set_resolution", "get_resolution");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "update_mode", PROPERTY_HINT_ENUM, "Once,Always"), "set_update_mode", "get_update_mode");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "virtual_objects_mask", PROPERTY_HINT_LAYERS_3D_RENDER), "set_virtual_objects_mask", "get_virtual_objects_mask");
	ADD_GROUP("Sources", "");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "coarse_model", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "CoarseRoomModel"), "set_coarse_model", "get_coarse_model");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "dense_slam", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "DenseSLAM"), "set_dense_slam", "get_dense_slam");
	ADD_GROUP("Output", "");
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "target_material", PROPERTY_HINT_RESOURCE_TYPE, "ShaderMaterial", PROPERTY_USAGE_DEFAULT, "ShaderMaterial"), "set_target_material", "get_target_material");
	ADD_PROPERTY(PropertyInfo(Variant::STRING_NAME, "material_parameter"), "set_material_parameter", "get_material_parameter");
	ADD_PROPERTY(PropertyInfo(Variant::STRING_NAME, "sh_parameter"), "set_sh_parameter", "get_sh_parameter");
	ADD_PROPERTY(PropertyInfo(Variant::STRING_NAME, "position_parameter"), "set_position_parameter", "get_position_parameter");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "sh_frame", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "Node3D"), "set_sh_frame", "get_sh_frame");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "reflection_probe", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "ReflectionProbe"), "set_reflection_probe", "get_reflection_probe");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "world_environment", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "WorldEnvironment"), "set_world_environment", "get_world_environment");

	BIND_ENUM_CONSTANT(UPDATE_ONCE);
	BIND_ENUM_CONSTANT(UPDATE_ALWAYS);

	ADD_SIGNAL(MethodInfo("environment_map_updated"));
}

} // namespace roomprobe
