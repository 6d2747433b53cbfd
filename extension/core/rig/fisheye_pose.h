#pragma once
// The fisheye's pose at one of its frames (paper §4.3): the two cameras are not synchronised, so
// the RGB-D pose is interpolated at the fisheye's capture instant, then the fixed extrinsic applied.

#include "rig.h"
#include "trajectory.h"

#include <string>

namespace roomprobe {

// p_fisheye_timestamp_s is on the fisheye's clock; p_rig.fisheye_time_offset_s takes it to the
// RGB-D clock of p_rgb_trajectory (world_from_rgb). world_from_fisheye = world_from_rgb(t + offset)
// * rgb_from_fisheye. False, with r_error naming both times, outside the trajectory (beyond
// p_extrapolation_tolerance_s, see Trajectory::pose_at); r_world_from_fisheye is then unchanged.
bool fisheye_pose_at(const Trajectory &p_rgb_trajectory, const Rig &p_rig, double p_fisheye_timestamp_s,
		Pose *r_world_from_fisheye, std::string *r_error, double p_extrapolation_tolerance_s = 0.0);

} // namespace roomprobe
