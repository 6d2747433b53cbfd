#pragma once
// Plain data shared by the dense SLAM stages (paper §4.2): what the model's raycast gives and
// what frame-to-model tracking takes, and each frame's tracking state.

#include <camera/pinhole_camera.h>
#include <io/opencv.h>
#include <math/pose.h>

#include <string>

namespace roomprobe {

// Axial noise of a depth reading at z metres: sigma(z) = a + b (z - c)^2 metres (Nguyen et al.
// 2012, a Kinect; the synthetic rig's depth uses the same model). Tracking weighs a reading by
// min(1, sigma(reference_m) / sigma(z)): readings nearer than reference_m weigh 1, farther ones
// less, so that far readings count by their noise instead of being cut. b = 0: all weigh 1.
struct DepthNoiseModel {
	double a_m = 0.0012;
	double b_per_m2 = 0.0019;
	double c_m = 0.4;
	double reference_m = 0.5;
	double sigma_m(double p_z_m) const { return a_m + b_per_m2 * (p_z_m - c_m) * (p_z_m - c_m); }
};

// The dense model seen from one camera pose: the raycast of the TSDF (tsdf_volume.h), and the
// reference that ICP (icp_tracker.h) aligns the next depth frame to. All maps have the camera's
// size; a pixel whose ray met no surface holds NaN in points and normals (and 0 in colors).
struct ModelMaps {
	PinholeIntrinsics camera; // the camera the maps were cast for (undistorted)
	Pose world_from_camera; // the pose they were cast from
	cv::Mat points; // CV_32FC3, world metres
	cv::Mat normals; // CV_32FC3, world, unit length, pointing towards the camera
	cv::Mat colors; // CV_8UC3, R, G, B
	cv::Mat depth; // CV_32FC1, metres along the camera's optical axis (z), NaN where no hit
};

// How tracking went for one frame.
enum class TrackingState {
	Good, // the pose is trusted; the frame may be integrated
	Poor, // a pose was found but with little support; integrate nothing, keep going
	Lost, // no trustworthy pose: the last good pose is held and nothing is integrated
};

const char *tracking_state_name(TrackingState p_state); // "good", "poor", "lost"

struct TrackingResult {
	TrackingState state = TrackingState::Lost;
	std::string reason; // why Poor or Lost, for people ("too few valid depth pixels: 0 of 307200")
	Pose world_from_camera; // the estimate (the held pose when Lost)
	double inlier_fraction = 0.0; // inlier correspondences / valid depth pixels, at the finest level
	double rmse_m = 0.0; // point-to-plane RMS residual of the inliers at the finest level, metres
	int iterations = 0; // Gauss-Newton iterations over all levels
	// The weakest direction's share of the information at the final pose (icp_tracker.h
	// min_constraint; geometry, plus colour where it was used): about 0.3 for a room corner seen
	// whole, near 0 for a flat wall.
	double constraint = 0.0;
	bool colour_used = false; // the photometric rows took part at the finest level
	// Poor only because a direction is unconstrained (kept at the guess, icp_tracker.h), the
	// support otherwise good (inliers and residual within the Good limits).
	bool unconstrained = false;
	// Poor because the colour term moved the pose along a direction the geometry leaves free
	// farther than IcpOptions::max_colour_slide_m / _deg allow: the pose is the guess along it.
	bool colour_held = false;
	bool relocalised = false; // found by the wider search after a loss (dense_slam.h)
};

} // namespace roomprobe
