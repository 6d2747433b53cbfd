#pragma once
// CoarseRoomModel: the room as its floorplan extruded to the ceiling (§4.1), shown as a mesh
// with one texture atlas. The mesh is rebuilt, in the editor too, whenever the floorplan changes.
// It gives the room to the live engine (engine/live_room.h) of its RigCapture, which textures it
// from every fisheye frame (§4.3-§4.6) on its coarse worker; this node shows the newest atlas.
// Without a RigCapture it holds a room-only engine of its own, for set_atlas_image.

#include "live_room_link.h"

#include <engine/live_room.h>
#include <engine/room_sweep.h>
#include <room/floorplan.h>
#include <room/room_mesh.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

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
		FLOORPLAN_AUTOMATIC, // found from the sweep by the live engine (issue #18), refined as it goes on
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
	void set_floorplan_source(int64_t p_source);
	FloorplanSource get_floorplan_source() const;
	void set_texel_size(double p_metres);
	double get_texel_size() const;

	void set_rig_capture_path(const godot::NodePath &p_path);
	godot::NodePath get_rig_capture_path() const;
	void set_dense_slam_path(const godot::NodePath &p_path);
	godot::NodePath get_dense_slam_path() const;
	void set_pose_source(int64_t p_source);
	PoseSource get_pose_source() const;
	void set_inpainting(bool p_enabled);
	bool get_inpainting() const;
	void set_lighting_compensation(int64_t p_mode);
	LightingCompensation get_lighting_compensation() const;
	void set_room_layers(int64_t p_layers);
	uint32_t get_room_layers() const;

	// Shows the engine's newest coarse atlas if it has not been shown yet (signals
	// texture_updated); true when it did. Called every frame while the node processes.
	bool integrate_rig_frame();
	int64_t get_integrated_frame_count() const;
	godot::Dictionary get_last_frame_stats() const;
	// The room found from the sweep (Automatic): per floorplan edge, the share seen as a wall (0: the
	// room ends there only because the view did); empty in the other sources.
	godot::PackedFloat32Array get_wall_confidence() const;
	// The newest estimate: state, message, version, ceiling_source, fused_frames, fisheye_views, seconds.
	godot::Dictionary get_room_estimate() const;
	// Estimates the room now on the calling thread (seconds; tests, headless tools, a Step-paced
	// RigCapture whose engine has no worker) and applies it as Automatic does. False: no room yet.
	bool estimate_room_now();
	// The editor's way to the room of a recording: finds the room of p_path (empty: the
	// RigCapture's recording_path) on a worker thread (about a minute for a 10-s sweep; the
	// engine/room_sweep.h of ./roomprobe room), then applies it as Automatic does, placed in the
	// recording's world. False, with an error, when one is running or the path is unusable.
	bool find_room_in_recording(const godot::String &p_path);
	bool is_finding_room() const;
	// Waits for the search and applies its room (tests, headless tools). False: no room found.
	bool finish_room_search();

	// Writes the room shown (floorplan, ceiling, the first camera's pose and the probes, in the
	// room's frame) as a room.yaml. An existing file is kept unless p_overwrite.
	godot::Error save_room(const godot::String &p_path, bool p_overwrite = false);

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
	static constexpr double CEILING_HEIGHT_MIN_M = 0.5, CEILING_HEIGHT_MAX_M = 100.0; // as the property's hint
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
	// FLOORPLAN_AUTOMATIC: takes the engine's newest room estimate when it differs enough.
	void take_found_room();
	// p_world_from_model: the world's pose of the frame the room was found in (the engine's world:
	// identity; a recording's first camera: its initial_rgb_pose).
	void apply_found_room(const FoundRoom &p_found, const Pose &p_world_from_model = Pose());
	void take_room_search(); // a finished search's room, applied (main thread)
	bool worse_than_shown(const FoundRoom &p_candidate) const;
	// A room search on a recording (find_room_in_recording): the worker writes result, then done.
	struct RoomSearch {
		std::thread thread;
		std::atomic<bool> cancel{ false };
		std::atomic<bool> done{ false };
		std::string recording;
		RoomSweepResult result;
	};
	std::unique_ptr<RoomSearch> search;
	void stop_room_search(); // cancels and joins (the node's destruction; leaving the tree keeps it running)
	std::shared_ptr<const FoundRoom> looked_at; // the engine's estimate last looked at
	std::shared_ptr<const FoundRoom> found; // and last applied (its room shown)
	std::shared_ptr<const FoundRoom> searched; // the last recording search's result
	godot::PackedFloat32Array wall_confidence;
	// The room's frame in the world: the node's global transform (rigid part).
	Pose world_from_room() const;
	uint32_t room_layers = 1u << 19; // layer 20: probes see it, the AR camera (DenseSLAM) not

	std::shared_ptr<LiveRoom> engine;
	bool own_engine = false; // no RigCapture: a room-only engine
	std::string pushed; // what push_room last gave the engine, to skip repeats
	std::shared_ptr<const CoarseSnapshot> shown; // the atlas on the mesh
	cv::Mat hook_atlas; // the last set_atlas_image texture (a room-only engine puts it back after a reconfigure)
	std::string hook_layout; // the atlas layout it belongs to
	std::string pushed_layout; // the atlas layout push_room last gave the engine
	std::string pushed_options; // the options push_room last gave the engine
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::PoseSource)
VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::LightingCompensation)
VARIANT_ENUM_CAST(roomprobe::CoarseRoomModel::FloorplanSource)
