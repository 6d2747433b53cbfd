#pragma once
// The room found from a recorded sweep (issue #18): a recording's RGB-D frames through LiveRoom,
// the one live system (dense SLAM only: no room is known yet), then its find_room_now (the
// room/room_from_sweep.h steps) with fisheye frames spread over the sweep. roomprobe_room and
// the tests run this; a live session's engine finds the room itself (LiveRoomConfig::find_room).

#include <engine/live_room.h>
#include <recording/recording_reader.h>
#include <room/room_estimation.h>

#include <atomic>
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
	float max_depth_m = FIND_ROOM_MAX_DEPTH_M; // depth fused this far, metres
	RoomEstimationOptions estimation;
	std::function<void(const std::string &)> progress; // a line per stage; null: quiet
	// Set from another thread to stop early (the editor closing): the result then says "cancelled".
	const std::atomic<bool> *cancel = nullptr;
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

RoomSweepResult sweep_room(const RoomSweepOptions &p_options);

} // namespace roomprobe
