#pragma once
// The room from what a sweep observed (issue #18): room_estimation.h's steps in order, on the
// dense model's surface, the RGB-D camera's path and fisheye views posed in the same frame (the
// dense model's, "model" below). The live engine (engine/live_room.h find_room_now) and
// roomprobe_room (engine/room_sweep.h) both call this one function.

#include "room_estimation.h"

#include <string>
#include <vector>

namespace roomprobe {

// Depth is fused at least this far (metres) while the room is being found: its far walls matter
// here, while the maps' dense model keeps to nearby surfaces (TsdfOptions' default, 4 m).
inline constexpr float FIND_ROOM_MAX_DEPTH_M = 6.0f;

struct SweepObservations {
	std::vector<SurfaceSample> samples; // the dense surface, model frame
	std::vector<glm::dvec3> camera_positions; // the RGB-D camera's path, model frame
	bool has_first_camera = false;
	Pose model_from_first_rgb; // the RGB camera at the sweep's first tracked frame
	glm::dvec3 up_hint = glm::dvec3(0.0, 1.0, 0.0); // roughly up, model frame (the upward fisheye's axis)
	bool has_fisheye = false;
	OmniParams fisheye;
	std::vector<FisheyeView> fisheye_views; // posed in the model frame
};

struct RoomFromSweep {
	RoomEstimate estimate; // its world_from_model maps the model frame into the room found
	CeilingSearch fisheye_ceiling; // tried when the dense model held no ceiling
	std::vector<std::string> fisheye_walls; // the edges never seen as walls, searched in the fisheye
	// A room to use: a floorplan and a ceiling height (Complete or Partial with a ceiling).
	bool has_room = false;
	Pose initial_rgb_pose; // the first RGB camera in the room found (room.yaml's initial_rgb_pose)
};

// Up, roughly, in the model frame at the first camera: the upward fisheye's axis when the rig has
// one (p_rgb_from_fisheye), else the RGB camera's -y (held upright).
glm::dvec3 sweep_up_hint(const Pose &p_model_from_first_rgb, bool p_has_fisheye, const Pose &p_rgb_from_fisheye);

// The first RGB camera's pose in a world no room file gives (a live rig's first run, a recording
// without room.yaml): at the origin, held upright, so the world is Y up from the first frame to
// within the rig's tilt: the hint above (the fisheye's axis) is +Y, and the camera's view,
// levelled, looks down -Z, Godot's forward. Not the identity: that world is the camera's own,
// y down, and Godot would show it upside down. The room found later places itself in it.
Pose upright_first_rgb_pose(bool p_has_fisheye, const Pose &p_rgb_from_fisheye);

// Steps 1 to 3 and the walls never seen (room_estimation.h). Throws nothing: CGAL's or OpenCV's
// exceptions become a NoSurface estimate whose message names them.
RoomFromSweep find_room_from_sweep(const SweepObservations &p_observed, const RoomEstimationOptions &p_options);

} // namespace roomprobe
