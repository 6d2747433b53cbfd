#include "room_probe.h"

using namespace godot;

namespace roomprobe {

void RoomProbe::set_resolution(int p_texels) { resolution = p_texels; }
int RoomProbe::get_resolution() const { return resolution; }

void RoomProbe::set_coarse_model_path(const NodePath &p_path) {
	coarse_model_path = p_path;
	update_configuration_warnings();
}

NodePath RoomProbe::get_coarse_model_path() const { return coarse_model_path; }
void RoomProbe::set_dense_slam_path(const NodePath &p_path) { dense_slam_path = p_path; }
NodePath RoomProbe::get_dense_slam_path() const { return dense_slam_path; }

PackedStringArray RoomProbe::get_warnings() const {
	PackedStringArray warnings;
	warnings.push_back("Environment-map synthesis is not implemented yet (issue #4): RoomProbe outputs no cubemap.");
	if (coarse_model_path.is_empty()) {
		warnings.push_back("Set coarse_model to the CoarseRoomModel of the room.");
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

	ADD_PROPERTY(PropertyInfo(Variant::INT, "resolution", PROPERTY_HINT_ENUM, "64:64,128:128,256:256,512:512"), "set_resolution", "get_resolution");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "coarse_model", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "CoarseRoomModel"), "set_coarse_model", "get_coarse_model");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "dense_slam", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "DenseSLAM"), "set_dense_slam", "get_dense_slam");

	ADD_SIGNAL(MethodInfo("environment_map_updated"));
}

} // namespace roomprobe
