#pragma once
// RoomProbe: a point where an environment map of the live room is synthesised (§4.7),
// as a cubemap and 5-band spherical harmonics (§4.8).

#include <coarse/lighting.h>
#include <envmap/coarse_render.h>
#include <envmap/dense_render.h>
#include <envmap/spherical_harmonics.h>

#include <rp_godot/godot.h>

#include <cstdint>
#include <memory>

namespace roomprobe {

class CoarseRoomModel;
class DenseSLAM;

class RoomProbe : public godot::Node3D {
	GDCLASS(RoomProbe, godot::Node3D)

public:
	enum UpdateMode {
		UPDATE_ONCE,
		UPDATE_ALWAYS,
	};

	RoomProbe();
	~RoomProbe();

	void set_resolution(int p_texels);
	int get_resolution() const;
	void set_coarse_model_path(const godot::NodePath &p_path);
	godot::NodePath get_coarse_model_path() const;
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;
	void set_update_mode(UpdateMode p_mode);
	UpdateMode get_update_mode() const;
	void set_target_material(const godot::Ref<godot::ShaderMaterial> &p_material);
	godot::Ref<godot::ShaderMaterial> get_target_material() const;
	void set_material_parameter(const godot::StringName &p_name);
	godot::StringName get_material_parameter() const;
	void set_sh_parameter(const godot::StringName &p_name);
	godot::StringName get_sh_parameter() const;
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
	// What the last update_now() did: dense_texels (int), dense_ms, update_ms (float).
	godot::Dictionary get_last_update_stats() const;
	// The latest map as an EXR strip (32-bit float, recording/cubemap_layout.h) or as an 8-bit
	// PNG cross (envmap/export.h). Paths may be res:// or user:// or absolute. Error codes as
	// Godot's; the message names the file.
	godot::Error save_exr(const godot::String &p_path) const;
	godot::Error save_png_net(const godot::String &p_path) const;
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
	CoarseRoomModel *find_coarse_model() const;
	DenseSLAM *find_dense_slam() const;
	// §4.7's second pass: the dense model over the coarse render, with the lighting change since
	// its colours were last refreshed.
	void render_dense(const CoarseRoomModel &p_model, roomprobe::Cubemap *io_map);
	void apply_to_material();
	// Route (b): places and sets up the ReflectionProbe so that it sees the textured room only.
	void drive_reflection_probe(const CoarseRoomModel &p_model);
	// Route (c): the map as the WorldEnvironment's sky (reflections and ambient light).
	void drive_world_environment();

	int resolution = 256;
	godot::NodePath coarse_model_path;
	godot::NodePath dense_slam_path;
	UpdateMode update_mode = UPDATE_ONCE;
	godot::Ref<godot::ShaderMaterial> target_material;
	godot::StringName material_parameter = "environment";
	godot::StringName sh_parameter = "sh";
	godot::NodePath reflection_probe_path;
	godot::NodePath world_environment_path;
	godot::Ref<godot::ShaderMaterial> sky_material;
	godot::Ref<godot::Sky> sky;

	// The renderer caches the surface texels of one mesh version of one model.
	std::unique_ptr<CoarseCubemapRenderer> renderer;
	uint64_t renderer_mesh_version = 0;

	roomprobe::Cubemap last_map; // as rendered, for export
	godot::Ref<godot::Image> faces[6]; // RGBF, as rendered
	godot::Ref<godot::Cubemap> cubemap; // RGBAH with mipmaps
	ShCoefficients sh{};
	DenseLighting dense_lighting;
	DenseRenderStats dense_stats;
	double update_ms = 0.0;
	bool has_map = false;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RoomProbe::UpdateMode)
