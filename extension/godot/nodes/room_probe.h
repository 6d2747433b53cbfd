#pragma once
// RoomProbe: a point where an environment map of the live room is synthesised (§4.7),
// as a cubemap and 5-band spherical harmonics.

#include <rp_godot/godot.h>

namespace roomprobe {

class RoomProbe : public godot::Node3D {
	GDCLASS(RoomProbe, godot::Node3D)

public:
	void set_resolution(int p_texels);
	int get_resolution() const;
	void set_coarse_model_path(const godot::NodePath &p_path);
	godot::NodePath get_coarse_model_path() const;
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();

private:
	int resolution = 256;
	godot::NodePath coarse_model_path;
	godot::NodePath dense_slam_path;
};

} // namespace roomprobe
