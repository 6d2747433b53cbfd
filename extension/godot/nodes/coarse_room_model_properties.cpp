// CoarseRoomModel's properties (coarse_room_model.h): their setters, with the checks of
// property_checks.h, their getters, and the class's bindings. Split from coarse_room_model.cpp to
// keep each file short.
#include "coarse_room_model.h"

#include "../property_checks.h"

#include <cmath>
#include <cstdio>

using namespace godot;

namespace roomprobe {

void CoarseRoomModel::set_floorplan(const PackedVector2Array &p_points) {
	for (int64_t i = 0; i < p_points.size(); i++) {
		if (!std::isfinite(p_points[i].x) || !std::isfinite(p_points[i].y)) {
			char text[160];
			std::snprintf(text, sizeof(text), "CoarseRoomModel.floorplan: corner %lld is (%g, %g), not a finite point; the floorplan was left as it was", (long long)i,
					double(p_points[i].x), double(p_points[i].y));
			ERR_PRINT(text);
			return;
		}
	}
	floorplan = p_points;
	rebuild();
}

PackedVector2Array CoarseRoomModel::get_floorplan() const { return floorplan; }

void CoarseRoomModel::set_ceiling_height(double p_metres) {
	ceiling_height = property_checks::clamped("CoarseRoomModel.ceiling_height", p_metres, CEILING_HEIGHT_MIN_M, CEILING_HEIGHT_MAX_M, ceiling_height, " m");
	rebuild();
}

double CoarseRoomModel::get_ceiling_height() const { return ceiling_height; }

void CoarseRoomModel::set_floorplan_source(int64_t p_source) {
	if (!property_checks::enum_in_range("CoarseRoomModel.floorplan_source", p_source, 3)) {
		return;
	}
	floorplan_source = FloorplanSource(p_source);
	if (floorplan_source != FLOORPLAN_AUTOMATIC) {
		found.reset();
		wall_confidence.clear();
	}
	take_recording_room();
	push_room(); // the engine finds the room only for Automatic
	update_configuration_warnings();
}

CoarseRoomModel::FloorplanSource CoarseRoomModel::get_floorplan_source() const { return floorplan_source; }

void CoarseRoomModel::set_texel_size(double p_metres) {
	texel_size = property_checks::clamped("CoarseRoomModel.texel_size", p_metres, TEXEL_SIZE_MIN_M, TEXEL_SIZE_MAX_M, texel_size, " m");
	rebuild();
}

double CoarseRoomModel::get_texel_size() const { return texel_size; }

// ---------------------------------------------------------------- texturing from the rig (§4.3-§4.6)

void CoarseRoomModel::set_rig_capture_path(const NodePath &p_path) {
	rig_capture_path = p_path;
	if (is_inside_tree()) {
		connect_engine();
	}
	update_configuration_warnings();
}

NodePath CoarseRoomModel::get_rig_capture_path() const { return rig_capture_path; }

void CoarseRoomModel::set_pose_source(int64_t p_source) {
	if (!property_checks::enum_in_range("CoarseRoomModel.pose_source", p_source, 2)) {
		return;
	}
	pose_source = PoseSource(p_source);
	push_room();
	update_configuration_warnings();
}

CoarseRoomModel::PoseSource CoarseRoomModel::get_pose_source() const { return pose_source; }

void CoarseRoomModel::set_dense_slam_path(const NodePath &p_path) {
	dense_slam_path = p_path;
	update_configuration_warnings();
}

NodePath CoarseRoomModel::get_dense_slam_path() const { return dense_slam_path; }

void CoarseRoomModel::set_inpainting(bool p_enabled) {
	inpainting = p_enabled;
	push_room();
}

bool CoarseRoomModel::get_inpainting() const { return inpainting; }

void CoarseRoomModel::set_lighting_compensation(int64_t p_mode) {
	if (!property_checks::enum_in_range("CoarseRoomModel.lighting_compensation", p_mode, 3)) {
		return;
	}
	lighting_compensation = LightingCompensation(p_mode);
	push_room();
}

CoarseRoomModel::LightingCompensation CoarseRoomModel::get_lighting_compensation() const { return lighting_compensation; }

void CoarseRoomModel::set_room_layers(int64_t p_layers) {
	room_layers = property_checks::render_layers("CoarseRoomModel.room_layers", p_layers);
	if (mesh_instance != nullptr) {
		mesh_instance->set_layer_mask(room_layers);
	}
}

uint32_t CoarseRoomModel::get_room_layers() const { return room_layers; }

void CoarseRoomModel::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &CoarseRoomModel::get_warnings);
	ClassDB::bind_method(D_METHOD("set_floorplan", "points"), &CoarseRoomModel::set_floorplan);
	ClassDB::bind_method(D_METHOD("get_floorplan"), &CoarseRoomModel::get_floorplan);
	ClassDB::bind_method(D_METHOD("set_ceiling_height", "metres"), &CoarseRoomModel::set_ceiling_height);
	ClassDB::bind_method(D_METHOD("get_ceiling_height"), &CoarseRoomModel::get_ceiling_height);
	ClassDB::bind_method(D_METHOD("set_texel_size", "metres"), &CoarseRoomModel::set_texel_size);
	ClassDB::bind_method(D_METHOD("get_texel_size"), &CoarseRoomModel::get_texel_size);
	ClassDB::bind_method(D_METHOD("is_valid"), &CoarseRoomModel::is_valid);
	ClassDB::bind_method(D_METHOD("get_floorplan_error"), &CoarseRoomModel::get_floorplan_error);
	ClassDB::bind_method(D_METHOD("get_mesh"), &CoarseRoomModel::get_mesh);
	ClassDB::bind_method(D_METHOD("get_atlas_size"), &CoarseRoomModel::get_atlas_size);
	ClassDB::bind_method(D_METHOD("set_atlas_image", "image"), &CoarseRoomModel::set_atlas_image);
	ClassDB::bind_method(D_METHOD("get_atlas_image"), &CoarseRoomModel::get_atlas_image);
	ClassDB::bind_method(D_METHOD("has_texture_data"), &CoarseRoomModel::has_texture_data);
	ClassDB::bind_method(D_METHOD("get_charts"), &CoarseRoomModel::get_charts);
	ClassDB::bind_method(D_METHOD("set_rig_capture", "path"), &CoarseRoomModel::set_rig_capture_path);
	ClassDB::bind_method(D_METHOD("get_rig_capture"), &CoarseRoomModel::get_rig_capture_path);
	ClassDB::bind_method(D_METHOD("set_dense_slam", "path"), &CoarseRoomModel::set_dense_slam_path);
	ClassDB::bind_method(D_METHOD("get_dense_slam"), &CoarseRoomModel::get_dense_slam_path);
	ClassDB::bind_method(D_METHOD("set_floorplan_source", "source"), &CoarseRoomModel::set_floorplan_source);
	ClassDB::bind_method(D_METHOD("get_floorplan_source"), &CoarseRoomModel::get_floorplan_source);
	ClassDB::bind_method(D_METHOD("set_pose_source", "source"), &CoarseRoomModel::set_pose_source);
	ClassDB::bind_method(D_METHOD("get_pose_source"), &CoarseRoomModel::get_pose_source);
	ClassDB::bind_method(D_METHOD("set_inpainting", "enabled"), &CoarseRoomModel::set_inpainting);
	ClassDB::bind_method(D_METHOD("get_inpainting"), &CoarseRoomModel::get_inpainting);
	ClassDB::bind_method(D_METHOD("set_lighting_compensation", "mode"), &CoarseRoomModel::set_lighting_compensation);
	ClassDB::bind_method(D_METHOD("get_lighting_compensation"), &CoarseRoomModel::get_lighting_compensation);
	ClassDB::bind_method(D_METHOD("set_room_layers", "layers"), &CoarseRoomModel::set_room_layers);
	ClassDB::bind_method(D_METHOD("get_room_layers"), &CoarseRoomModel::get_room_layers);
	ClassDB::bind_method(D_METHOD("integrate_rig_frame"), &CoarseRoomModel::integrate_rig_frame);
	ClassDB::bind_method(D_METHOD("get_integrated_frame_count"), &CoarseRoomModel::get_integrated_frame_count);
	ClassDB::bind_method(D_METHOD("get_last_frame_stats"), &CoarseRoomModel::get_last_frame_stats);
	ClassDB::bind_method(D_METHOD("reset_texture"), &CoarseRoomModel::reset_texture);
	ClassDB::bind_method(D_METHOD("finish_inpainting"), &CoarseRoomModel::finish_inpainting);
	ClassDB::bind_method(D_METHOD("get_wall_confidence"), &CoarseRoomModel::get_wall_confidence);
	ClassDB::bind_method(D_METHOD("get_room_estimate"), &CoarseRoomModel::get_room_estimate);
	ClassDB::bind_method(D_METHOD("estimate_room_now"), &CoarseRoomModel::estimate_room_now);
	ClassDB::bind_method(D_METHOD("save_room", "path", "overwrite"), &CoarseRoomModel::save_room, false);
	ClassDB::bind_method(D_METHOD("find_room_in_recording", "path"), &CoarseRoomModel::find_room_in_recording, String());
	ClassDB::bind_method(D_METHOD("is_finding_room"), &CoarseRoomModel::is_finding_room);
	ClassDB::bind_method(D_METHOD("finish_room_search"), &CoarseRoomModel::finish_room_search);

	ADD_GROUP("Room", "");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "floorplan_source", PROPERTY_HINT_ENUM, "Manual,Recording,Automatic"), "set_floorplan_source", "get_floorplan_source");
	ADD_PROPERTY(PropertyInfo(Variant::PACKED_VECTOR2_ARRAY, "floorplan"), "set_floorplan", "get_floorplan");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "ceiling_height", PROPERTY_HINT_RANGE, "0.5,100,0.01,exp,suffix:m"), "set_ceiling_height", "get_ceiling_height");
	ADD_GROUP("Sources", "");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "rig_capture", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "RigCapture"), "set_rig_capture", "get_rig_capture");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "dense_slam", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "DenseSLAM"), "set_dense_slam", "get_dense_slam");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "pose_source", PROPERTY_HINT_ENUM, "Ground Truth,Dense SLAM"), "set_pose_source", "get_pose_source");
	ADD_GROUP("Texture", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "texel_size", PROPERTY_HINT_RANGE, "0.001,1,0.001,exp,suffix:m"), "set_texel_size", "get_texel_size");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "inpainting"), "set_inpainting", "get_inpainting");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "lighting_compensation", PROPERTY_HINT_ENUM, "Off,Additive (paper),Gain"), "set_lighting_compensation", "get_lighting_compensation");
	ADD_GROUP("Rendering", "");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "room_layers", PROPERTY_HINT_LAYERS_3D_RENDER), "set_room_layers", "get_room_layers");

	BIND_ENUM_CONSTANT(POSE_SOURCE_GROUND_TRUTH);
	BIND_ENUM_CONSTANT(POSE_SOURCE_DENSE_SLAM);
	BIND_ENUM_CONSTANT(LIGHTING_OFF);
	BIND_ENUM_CONSTANT(LIGHTING_ADDITIVE);
	BIND_ENUM_CONSTANT(LIGHTING_GAIN);
	BIND_ENUM_CONSTANT(FLOORPLAN_MANUAL);
	BIND_ENUM_CONSTANT(FLOORPLAN_RECORDING);
	BIND_ENUM_CONSTANT(FLOORPLAN_AUTOMATIC);

	ADD_SIGNAL(MethodInfo("mesh_changed"));
	ADD_SIGNAL(MethodInfo("texture_updated", PropertyInfo(Variant::INT, "fisheye_frame")));
	ADD_SIGNAL(MethodInfo("room_estimated", PropertyInfo(Variant::STRING, "state"), PropertyInfo(Variant::STRING, "message")));
}

} // namespace roomprobe
