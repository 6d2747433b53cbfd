#include "dense_slam.h"

using namespace godot;

namespace roomprobe {

void DenseSLAM::set_capture_path(const NodePath &p_path) {
	capture_path = p_path;
	update_configuration_warnings();
}

NodePath DenseSLAM::get_capture_path() const { return capture_path; }
void DenseSLAM::set_voxel_size(double p_metres) { voxel_size = p_metres; }
double DenseSLAM::get_voxel_size() const { return voxel_size; }
void DenseSLAM::set_truncation_distance(double p_metres) { truncation_distance = p_metres; }
double DenseSLAM::get_truncation_distance() const { return truncation_distance; }
DenseSLAM::TrackingState DenseSLAM::get_tracking_state() const { return tracking_state; }

PackedStringArray DenseSLAM::get_warnings() const {
	PackedStringArray warnings;
	warnings.push_back("Tracking and the dense model are not implemented yet (issue #5): DenseSLAM gives no pose.");
	if (capture_path.is_empty()) {
		warnings.push_back("Set capture to a RigCapture node.");
	}
	return warnings;
}

void DenseSLAM::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &DenseSLAM::get_warnings);
	ClassDB::bind_method(D_METHOD("set_capture", "path"), &DenseSLAM::set_capture_path);
	ClassDB::bind_method(D_METHOD("get_capture"), &DenseSLAM::get_capture_path);
	ClassDB::bind_method(D_METHOD("set_voxel_size", "metres"), &DenseSLAM::set_voxel_size);
	ClassDB::bind_method(D_METHOD("get_voxel_size"), &DenseSLAM::get_voxel_size);
	ClassDB::bind_method(D_METHOD("set_truncation_distance", "metres"), &DenseSLAM::set_truncation_distance);
	ClassDB::bind_method(D_METHOD("get_truncation_distance"), &DenseSLAM::get_truncation_distance);
	ClassDB::bind_method(D_METHOD("get_tracking_state"), &DenseSLAM::get_tracking_state);

	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "capture", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "RigCapture"), "set_capture", "get_capture");
	ADD_GROUP("Volume", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "voxel_size", PROPERTY_HINT_RANGE, "0.002,0.1,0.001,suffix:m"), "set_voxel_size", "get_voxel_size");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "truncation_distance", PROPERTY_HINT_RANGE, "0.005,0.5,0.001,suffix:m"), "set_truncation_distance", "get_truncation_distance");

	BIND_ENUM_CONSTANT(TRACKING_NOT_STARTED);
	BIND_ENUM_CONSTANT(TRACKING_GOOD);
	BIND_ENUM_CONSTANT(TRACKING_POOR);
	BIND_ENUM_CONSTANT(TRACKING_LOST);

	ADD_SIGNAL(MethodInfo("tracking_state_changed", PropertyInfo(Variant::INT, "state"), PropertyInfo(Variant::STRING, "reason")));
}

} // namespace roomprobe
