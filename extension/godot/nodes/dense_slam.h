#pragma once
// DenseSLAM: tracks the RGB-D camera and keeps the dense colour model of nearby surfaces (§4.2).

#include <rp_godot/godot.h>

namespace roomprobe {

class DenseSLAM : public godot::Node3D {
	GDCLASS(DenseSLAM, godot::Node3D)

public:
	enum TrackingState {
		TRACKING_NOT_STARTED, // No frame has been tracked.
		TRACKING_GOOD,
		TRACKING_POOR,
		TRACKING_LOST,
	};

	void set_capture_path(const godot::NodePath &p_path);
	godot::NodePath get_capture_path() const;
	void set_voxel_size(double p_metres);
	double get_voxel_size() const;
	void set_truncation_distance(double p_metres);
	double get_truncation_distance() const;
	TrackingState get_tracking_state() const;

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();

private:
	godot::NodePath capture_path;
	double voxel_size = 0.01;
	double truncation_distance = 0.04;
	TrackingState tracking_state = TRACKING_NOT_STARTED;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::DenseSLAM::TrackingState)
