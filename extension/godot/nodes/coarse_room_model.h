#pragma once
// CoarseRoomModel: the room as its floorplan extruded to the ceiling (§4.1), shown as a mesh
// with one texture atlas. The mesh is rebuilt, in the editor too, whenever the floorplan changes.
// With a RigCapture, each new fisheye frame goes through the core's CoarsePipeline (§4.3-§4.6,
// pipeline/coarse_pipeline.h), inpainting on its worker thread; this node only feeds and shows it.

#include <coarse/coarse_texture.h>
#include <pipeline/coarse_pipeline.h>
#include <room/room_mesh.h>

#include <cstdint>
#include <memory>
#include <string>

#include <rp_godot/godot.h>

namespace roomprobe {

class DenseSLAM;
class RigCapture;

class CoarseRoomModel : public godot::Node3D {
	GDCLASS(CoarseRoomModel, godot::Node3D)

public:
	enum PoseSource {
		POSE_SOURCE_GROUND_TRUTH, // the recording's ground-truth RGB-D trajectory (evaluation mode)
		POSE_SOURCE_DENSE_SLAM, // DenseSLAM's tracked trajectory (the live mode)
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

	// Puts rig_capture's newest fisheye frame through the pipeline if it has not been yet; true
	// when it did. Called every frame while the node processes.
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

	// For RoomProbe (C++ only). get_room_mesh is null while the floorplan is invalid.
	const RoomMesh *get_room_mesh() const { return result.ok ? &result.mesh : nullptr; }
	// The atlas to show and render: the pipeline's completed texture once it has a frame, else
	// what set_atlas_image put in. CV_32FC3 linear R, G, B; empty without a valid room.
	const cv::Mat &get_atlas() const;
	// The lighting changes applied so far (identity without a pipeline), for the dense colours.
	LightingChange get_cumulative_lighting() const;
	// Changes (to a value never used before by any model) whenever the mesh is rebuilt.
	uint64_t get_mesh_version() const { return mesh_version; }

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
	RigCapture *find_rig_capture() const;
	bool fisheye_pose(const RigCapture &p_rig, double p_timestamp_s, Pose *r_pose, std::string *r_error) const;
	bool ensure_pipeline(const RigCapture &p_rig);
	bool pipeline_has_frames() const { return pipeline && pipeline->frame_count() > 0; }

	godot::PackedVector2Array floorplan;
	double ceiling_height = 2.5;
	double texel_size = 0.02;

	FloorplanCheck check;
	RoomMeshResult result;
	godot::Ref<godot::ArrayMesh> mesh;
	godot::MeshInstance3D *mesh_instance = nullptr;

	uint64_t mesh_version = 0;
	CoarseTexture texture; // the atlas's size while the mesh is valid, empty otherwise
	bool textured = false; // whether texture holds data (set_atlas_image so far)
	godot::Ref<godot::ImageTexture> atlas_texture;
	godot::Ref<godot::StandardMaterial3D> material;

	godot::NodePath rig_capture_path;
	godot::NodePath dense_slam_path;
	PoseSource pose_source = POSE_SOURCE_GROUND_TRUTH;
	bool inpainting = true;
	LightingCompensation lighting_compensation = LIGHTING_GAIN;
	uint32_t room_layers = 1;

	std::unique_ptr<CoarsePipeline> pipeline; // null until a rig delivers; reset by any change
	const void *pipeline_reader = nullptr; // the RecordingReader the pipeline was configured for
	int64_t last_fisheye_index = -1; // of the rig's fisheye stream, the last frame integrated
	CoarseFrameStats last_stats;
	std::string pipeline_problem; // why frames are not integrated (for the warnings), or empty
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::PoseSource)
VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::LightingCompensation)
