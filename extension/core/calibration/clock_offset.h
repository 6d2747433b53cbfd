#pragma once
// The clock offset between the RGB-D camera and the fisheye (Rig::fisheye_time_offset_s), from a
// recording of the rig moving by hand: both cameras are on one bracket, so they turn together.
//
//   1. The RGB-D camera's orientation over time: each frame's features (tracked by Lucas-Kanade
//      into the next frame) with their depth give that step's rotation (cv::solvePnPRansac).
//   2. The fisheye's rotation between consecutive frames, from its tracked features' rays
//      (camera/omni_camera.h) by the essential matrix (cv::findEssentialMat, cv::recoverPose):
//      insensitive to the small translation between frames.
//   3. The offset d that best explains each fisheye step by the RGB-D orientations at the
//      fisheye's times + d (slerp), through the rig's extrinsic rotation: least squares over the
//      three components of the rotation difference, a 2 ms grid over +-0.3 s, refined to 0.05 ms,
//      outliers (3 MADs) dropped once. Its standard deviation comes from the curvature there.
//
// Needs motion: a still rig, or one turning at constant speed about a fixed axis, does not fix d.

#include <recording/recording_reader.h>
#include <rig/rig.h>

#include <functional>
#include <string>

namespace roomprobe {

struct ClockOffsetOptions {
	double max_seconds = 6.0; // of the recording used, from its start (RGB-D clock)
	double search_s = 0.3; // |offset| searched
	std::function<void(const std::string &)> progress; // optional
};

struct ClockOffsetEstimate {
	std::string error; // why it could not be estimated
	double offset_s = 0.0; // add to a fisheye timestamp to get RGB-D clock time
	double std_s = 0.0; // one standard deviation
	size_t rgbd_steps = 0, fisheye_steps = 0; // rotations measured
	size_t steps_used = 0; // fisheye steps in the final fit
	double residual_rms_deg = 0.0; // per component, at the offset
	double turn_deg = 0.0; // the fisheye's total rotation over the steps used (how much motion there was)
};

ClockOffsetEstimate estimate_clock_offset(const RecordingReader &p_reader, const Rig &p_rig, const ClockOffsetOptions &p_options = ClockOffsetOptions());

} // namespace roomprobe
