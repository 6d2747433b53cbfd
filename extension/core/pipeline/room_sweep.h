#pragma once
// The room found from a sweep (issue #18): a recording's RGB-D frames through LiveRoom, the one
// live system (dense SLAM only: no room is known yet), then room/room_estimation.h on its dense
// model, and the ceiling from the fisheye when the RGB-D camera never saw it. roomprobe_room
// and the tests run this; a live session calls estimate_room_in_engine on its own engine.

#include <engine/live_room.h>
#include <recording/recording_reader.h>
#include <room/room_estimation.h>

#include <functional>
#include <string>
#include <vector>

namespace roomprobe {

struct RoomSweepOptions {
	std::string recording;
	// Fuse depth at the recording's true poses instead of tracking (isolates the room's
	// estimation from SLAM's drift; needs ground truth).
	bool true_poses = false;
	double max_seconds = 0.0; // only the sweep's first this many seconds (0: all of it)
	size_t fisheye_views = 24; // fisheye frames, evenly spread, searched for the ceiling's edge
	float voxel_size_m = 0.0f; // 0: DenseSlamOptions' default
	// Depth is fused this far (metres): the far walls of a room matter here, while the maps'
	// dense model keeps to nearby surfaces (TsdfOptions' default).
	float max_depth_m = 6.0f;
	RoomEstimationOptions estimation;
	std::function<void(const std::string &)> progress; // a line per stage; null: quiet
};

struct RoomSweepResult {
	bool ok = false; // the sweep ran (the estimate may still say what it could not find)
	std::string error; // names the recording and what is wrong
	RoomEstimate estimate;
	CeilingSearch fisheye_ceiling; // tried when the dense model held no ceiling
	std::vector<std::string> fisheye_walls; // the edges never seen as walls, searched in the fisheye
	Pose world_from_model; // = estimate.world_from_model
	// The recording's true world from the dense model's frame (true_poses: identity; tracked: the
	// true pose of the first RGB-D frame, where tracking starts); valid when has_truth.
	bool has_truth = false;
	Pose true_world_from_model;
	RoomInfo truth;
	RoomInfo room; // the room found, as room.yaml holds it (valid when the estimate has a floorplan)
	std::vector<SurfaceSample> samples; // the dense surface, model frame
	size_t rgbd_frames = 0;
};

// The estimate on an engine's current dense model, with the fisheye's ceiling edge searched in
// p_fisheye (frames with their timestamps, as recorded) when the model holds no ceiling.
RoomSweepResult estimate_room_in_engine(const LiveRoom &p_engine, const Rig &p_rig, const std::vector<FisheyeFrame> &p_fisheye,
		const RoomEstimationOptions &p_options);

RoomSweepResult sweep_room(const RoomSweepOptions &p_options);

} // namespace roomprobe
