#pragma once
// RoomProbe: a point where an environment map of the live room is synthesised (§4.7),
// as a cubemap and 5-band spherical harmonics (§4.8). The map is rendered by the live engine
// (engine/live_room.h) that its CoarseRoomModel uses, on the engine's probe worker while frames
// play in real time; this node only sends its position and uploads each finished map (half-float
// faces with their mip chain, built on the worker) into its Cubemap.

#include "live_room_link.h"

#include <rp_godot/godot.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace roomprobe {

class RoomProbe : public godot::Node3D {
	GDCLASS(RoomProbe, godot::Node3D)

public:
	enum UpdateMode {
		UPDATE_ONCE,
		UPDATE_ALWAYS,
	};

	RoomProbe();
	~RoomProbe();

	void set_resolution(int64_t p_texels);
	int get_resolution() const;
	void set_coarse_model_path(const godot::NodePath &p_path);
	godot::NodePath get_coarse_model_path() const;
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;
	void set_update_mode(int64_t p_mode);
	UpdateMode get_update_mode() const;
	// Takes any Material so that a wrong one is named (a StandardMaterial3D cannot read the map).
	void set_target_material(const godot::Ref<godot::Material> &p_material);
	godot::Ref<godot::ShaderMaterial> get_target_material() const;
	void set_material_parameter(const godot::StringName &p_name);
	godot::StringName get_material_parameter() const;
	void set_sh_parameter(const godot::StringName &p_name);
	godot::StringName get_sh_parameter() const;
	void set_position_parameter(const godot::StringName &p_name);
	godot::StringName get_position_parameter() const;
	void set_reflection_probe_path(const godot::NodePath &p_path);
	godot::NodePath get_reflection_probe_path() const;
	void set_world_environment_path(const godot::NodePath &p_path);
	godot::NodePath get_world_environment_path() const;

	// Renders the coarse model at the probe's position into the cubemap, projects it onto SH,
	// feeds target_material and emits environment_map_updated. False (with an error) when
	// there is no valid coarse model to render.
	bool update_now();
	godot::Ref<godot::Cubemap> get_cubemap() const;
	// Face p_layer (0..5: +X -X +Y -Y +Z -Z) of the latest map as RGBF, full precision, no mipmaps.
	godot::Ref<godot::Image> get_face_image(int p_layer) const;
	godot::PackedVector3Array get_sh_coefficients() const;
	// The same coefficients in the frame of p_basis (an object's global basis, orthonormalised):
	// what a PRTTransfer of a rotated object is dotted with (envmap/spherical_harmonics.h rotate_sh).
	godot::PackedVector3Array get_sh_coefficients_in(const godot::Basis &p_basis) const;
	void set_sh_frame_path(const godot::NodePath &p_path);
	godot::NodePath get_sh_frame_path() const;
	void set_virtual_objects_mask(int64_t p_mask);
	uint32_t get_virtual_objects_mask() const;
	// How many virtual objects the last map drew (see virtual_objects_mask).
	int get_virtual_object_count() const;
	// What the last update_now() did: dense_texels (int), dense_ms, update_ms (float).
	godot::Dictionary get_last_update_stats() const;
	// The latest map as an EXR strip (32-bit float, types/cubemap_layout.h) or as an 8-bit
	// PNG cross (envmap/export.h). Paths may be res:// or user:// or absolute. Error codes as
	// Godot's; the message names the file.
	godot::Error save_exr(const godot::String &p_path) const;
	godot::Error save_png_net(const godot::String &p_path) const;
	godot::Ref<godot::Image> get_net_image() const;
	// The sky material of the WorldEnvironment route (null until first used).
	godot::Ref<godot::ShaderMaterial> get_sky_material() const;

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

public:
	void _process(double p_delta);

private:
	// The engine of the CoarseRoomModel (by path, or the one in the scene); registers the probe.
	void connect_engine();
	void disconnect_engine();
	// Copies the engine's newest map of this probe into the Cubemap and the outputs; true when new.
	bool take_map();
	void place_in_engine();
	void apply_to_material();
	// Route (b): places and sets up the ReflectionProbe so that it sees the textured room only.
	void drive_reflection_probe();
	// Route (c): the map as the WorldEnvironment's sky (reflections and ambient light).
	void drive_world_environment();
	// Every property of a user's object (its material, ReflectionProbe, WorldEnvironment) the probe
	// sets goes through drive(), which keeps the value it had before the first change, so that
	// the scene saved in the editor holds the user's values, not the probe's maps
	// (NOTIFICATION_EDITOR_PRE_SAVE restores them all, POST_SAVE drives them again).
	void remember_original(const godot::Object *p_target, const godot::StringName &p_property, bool p_shader_parameter, const godot::Variant &p_current);
	void drive(godot::Object *p_target, const godot::StringName &p_property, const godot::Variant &p_value);
	void drive_shader_parameter(const godot::Ref<godot::ShaderMaterial> &p_material, const godot::StringName &p_name, const godot::Variant &p_value);
	void restore_driven();
	void drive_outputs();
	// The MeshInstance3Ds on virtual_objects_mask's layers, in this probe's viewport, less its own
	// object, handed to the engine when any of them changed (prt/virtual_objects.h).
	void refresh_virtual_objects();

	// Face sides the setter accepts (clamped with a warning outside).
	static constexpr int RESOLUTION_MIN = 8;
	static constexpr int RESOLUTION_MAX = 4096;
	int resolution = 256;
	godot::NodePath coarse_model_path;
	godot::NodePath dense_slam_path;
	UpdateMode update_mode = UPDATE_ONCE;
	godot::Ref<godot::ShaderMaterial> target_material;
	godot::StringName material_parameter = "environment";
	godot::StringName sh_parameter = "sh";
	godot::StringName position_parameter = "probe_position";
	godot::NodePath sh_frame_path; // a Node3D: the SH given to target_material are in its frame
	struct Driven {
		uint64_t object = 0; // instance id (a freed object is skipped)
		godot::StringName property; // a property, or a shader parameter with shader_parameter set
		bool shader_parameter = false;
		godot::Variant original;
	};
	std::vector<Driven> driven;
	uint32_t virtual_objects_mask = 0; // render layers of the virtual objects drawn into the map
	// What the objects were when last handed over: which instance, its mesh, material and transform.
	struct VirtualObjectKey {
		uint64_t instance = 0;
		const void *mesh = nullptr, *material = nullptr;
		godot::Transform3D transform;
		bool operator==(const VirtualObjectKey &p_other) const = default;
	};
	std::vector<VirtualObjectKey> virtual_objects_signature;
	int virtual_object_count = 0;
	godot::NodePath reflection_probe_path;
	godot::NodePath world_environment_path;
	godot::Ref<godot::ShaderMaterial> sky_material;
	godot::Ref<godot::Sky> sky;

	std::shared_ptr<LiveRoom> engine;
	uint64_t once_room_version = 0; // Once: the room (LiveRoom::room_version) its map was made in
	void process_once();
	int probe_id = 0;
	std::shared_ptr<const ProbeMap> map; // the one uploaded
	mutable godot::Ref<godot::Image> faces[6]; // RGBF, made on request
	godot::Ref<godot::Cubemap> cubemap; // RGBAH with mipmaps
	double upload_ms = 0.0;
	// Beyond this a probe is far outside its room (a little outside is a floorplan's slack).
	static constexpr double PROBE_OUTSIDE_WARNING_M = 0.5;
	bool outside_room = false;
	double outside_room_m = 0.0;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RoomProbe::UpdateMode)
