#pragma once
// OpenCV contrib's rgbd module as a peer of RoomProbe's dense SLAM stages (issue #11), run in the
// same process on the same frames, so that the ratios hold on any machine:
// - its voxel-hashed TSDF (cv::kinfu::makeVolume with VolumeType::HASHTSDF) integrates each frame
//   at the pose RoomProbe tracked, at RoomProbe's voxel size, truncation and depth range, then
//   raycasts the tracking reference's size (RoomProbe's raycast_level) from that pose;
// - cv::rgbd::ICPOdometry aligns each frame to the one before (depth only, its defaults).
// Timed apart from RoomProbe's engine, after it.

#include <camera/pinhole_camera.h>
#include <math/pose.h>

#include <io/opencv.h>

#include <string>
#include <vector>

namespace roomprobe::bench {

struct PeerFrame {
	cv::Mat depth_m; // CV_32FC1, metres, NaN or 0 where there is no reading (RgbdFrame::depth_m)
	Pose world_from_camera; // the pose RoomProbe's engine tracked
};

struct PeerSettings {
	PinholeIntrinsics camera; // the frames' (undistorted) camera
	float voxel_size_m = 0.01f;
	float truncation_m = 0.04f;
	float min_depth_m = 0.3f, max_depth_m = 4.0f; // readings outside are dropped before the peer sees them
	int max_weight = 64;
	int raycast_level = 2; // the raycast is at 1 / 2^level of the camera's size
};

struct PeerTimings {
	std::string volume; // the volume type that ran ("HASHTSDF")
	std::string error; // why a peer could not run (empty when both ran)
	std::vector<double> integrate_ms, raycast_ms, icp_ms; // one per frame (ICP: per pair)
	int raycast_width = 0, raycast_height = 0;
};

PeerTimings run_opencv_peers(const std::vector<PeerFrame> &p_frames, const PeerSettings &p_settings);

} // namespace roomprobe::bench
