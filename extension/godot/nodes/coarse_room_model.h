#pragma once
// CoarseRoomModel: the room as its floorplan extruded to the ceiling (§4.1), shown as a mesh
// with one texture atlas. The mesh is rebuilt, in the editor too, whenever the floorplan changes.
// It gives the room to the live engine (engine/live_room.h) of its RigCapture, which textures it
// from every fisheye frame (§4.3-§4.6) on its coarse worker; this node shows the newest atlas.
// Without a RigCapture it holds a room-only engine of its own, for set_atlas_image.

#include "live_room_link.h"

#include <room/floorplan.h>
#include <room/room_mesh.h>

#include <cstdint>
#include <memory>
#include <string>

#include <rp_godot/godot.h>

namespace roomprobe {

class CoarseRoomModel : public godot::Node3D, public LiveRoomHost {
	GDCLASS(CoarseRoomModel, godot::Node3D)

public:
	enum PoseSource {
		POSE_SOURCE_GROUND_TRUTH, // the recording's ground-truth RGB-D trajectory (evaluation mode)
		POSE_SOURCE_DENSE_SLAM, // DenseSLAM's tracked trajectory (the live mode)
	};
	enum FloorplanSource {
		FLOORPLAN_MANUAL, // floorplan and ceiling_height as set
		FLOORPLAN_RECORDING, // the recording's room.yaml, through the RigCapture (when it has one)
	};
	enum LightingCompensation {
		LIGHTING_OFF,
		LIGHTING_ADDITIVE, // the paper's §4.6: one offset per channel
		LIGHTING_GAIN, // a robust gain per channel
	};

	CoarseRoomModel();
	~CoarseRoomModel();

	void set_floorplan(const godot::PackedVector2Array &p_points);
	godot::PackedVector2Array get_floorplan() const;
	void set_ceiling_height(double p_metres);
	double get_ceiling_height() const;
	void set_floorplan_source(FloorplanSource p_source);
	FloorplanSource get_floorplan_source() const;
	void set_texel_size(double p_metres);
	double get_texel_size() const;

	void set_rig_capture_path(const godot::NodePath &p_path);
	godot::NodePath get_rig_capture_path() const;
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;
	void set_pose_source(PoseSource p_source);
	PoseSource get_pose_source() const;
	void set_inpainting(bool p_enabled);
	bool get_inpainting() const;
	void set_lighting_compensation(LightingCompensation p_mode);
	LightingCompensation get_lighting_compensation() const;
	void set_room_layers(uint32_t p_layers);
	uint32_t get_room_layers() const;

	// Shows the engine's newest coarse atlas if it has not been shown yet (signals
	// texture_updated); true when it did. Called every frame while the node processes.
	bool integrate_rig_frame();
	int64_t get_integrated_frame_count() const;
	godot::Dictionary get_last_frame_stats() const;
	// Forgets every observation (the atlas starts empty again).
	void reset_texture();
	// Waits for the inpainting worker's newest result and shows it (end of a recording, tests).
	void finish_inpainting();

	bool is_valid() const;
	godot::String get_floorplan_error() const;
	godot::Ref<godot::ArrayMesh> get_mesh() const;
	godot::Vector2i get_atlas_size() const;

	// The texture hook until the fisheye drives CoarseTexture (texture_update.h): puts a whole
	// atlas in (the atlas size, any uncompressed format; values taken as linear R, G, B, no sRGB
	// decoding) and marks every surface texel observed.
	bool set_atlas_image(const godot::Ref<godot::Image> &p_image);
	// The completed atlas as RGBF, or null while the model has no texture data.
	godot::Ref<godot::Image> get_atlas_image() const;
	bool has_texture_data() const;
	// One Dictionary per chart, in RoomMesh::charts order: kind ("wall", "floor", "ceiling"),
	// rect (Rect2i, atlas texels), normal (Vector3, into the room), wall_index (int, -1 if none).
	godot::Array get_charts() const;

	std::shared_ptr<LiveRoom> get_live_room() const override { return engine; }

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

public:
	void _process(double p_delta);

private:
	Floorplan core_floorplan() const; // the floorplan and ceiling height as the core takes them
	void rebuild();
	void apply_material();
	// The RigCapture's engine (by path, or the one RigCapture in the scene), else one of its own.
	void connect_engine();
	void push_room();
	bool take_snapshot();

	godot::PackedVector2Array floorplan;
	double ceiling_height = 2.5;
	// The texel sizes the setter accepts (clamped with a warning outside): finer makes atlases
	// beyond any GPU's texture limit for a room, coarser leaves a wall a handful of texels.
	static constexpr double TEXEL_SIZE_MIN_M = 0.001;
	static constexpr double TEXEL_SIZE_MAX_M = 1.0;
	double texel_size = 0.02;

	FloorplanCheck check;
	RoomMeshResult result;
	godot::Ref<godot::ArrayMesh> mesh;
	godot::MeshInstance3D *mesh_instance = nullptr;
	godot::Ref<godot::ImageTexture> atlas_texture;
	godot::Ref<godot::StandardMaterial3D> material;

	godot::NodePath rig_capture_path;
	godot::NodePath dense_slam_path;
	PoseSource pose_source = POSE_SOURCE_DENSE_SLAM;
	bool inpainting = true;
	LightingCompensation lighting_compensation = LIGHTING_GAIN;
	FloorplanSource floorplan_source = FLOORPLAN_MANUAL;
	// FLOORPLAN_RECORDING: takes the rig's room when it differs from the one shown.
	void take_recording_room();
	uint32_t room_layers = 1u << 19; // layer 20: probes see it, the AR camera (DenseSLAM) not

	std::shared_ptr<LiveRoom> engine;
	bool own_engine = false; // no RigCapture: a room-only engine
	std::string pushed; // what push_room last gave the engine, to skip repeats
	std::shared_ptr<const CoarseSnapshot> shown; // the atlas on the mesh
	cv::Mat hook_atlas; // the last set_atlas_image texture (a room-only engine puts it back after a reconfigure)
	std::string hook_layout; // the atlas layout it belongs to
	std::string pushed_layout; // the atlas layout push_room last gave the engine
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::PoseSource)
VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::LightingCompensation)
VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::FloorplanSource)
