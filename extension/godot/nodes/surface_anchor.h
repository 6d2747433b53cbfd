#pragma once
// SurfaceAnchor: puts itself, and so its children, down on the real surface below it once that
// surface is in the dense model (a ray straight down through the engine's Embree placement
// scene, placement/surface_placement.h). It replaces the demo's placement script: drop virtual
// objects under an anchor above the real table, press play.

#include "live_room_link.h"

#include <rp_godot/godot.h>

#include <memory>

namespace roomprobe {

class SurfaceAnchor : public godot::Node3D {
	GDCLASS(SurfaceAnchor, godot::Node3D)

public:
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;
	void set_search_height(double p_metres);
	double get_search_height() const;
	bool is_placed() const;
	// Looks for the surface again from where the anchor is now (after moving it by hand).
	void reset();

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }
	void _notification(int p_what);
	void _process(double p_delta);

protected:
	static void _bind_methods();

private:
	godot::NodePath dense_slam_path;
	double search_height = 1.0; // metres above the anchor the ray starts
	bool placed = false;
};

} // namespace roomprobe
