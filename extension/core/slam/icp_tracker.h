#pragma once
// Frame-to-model tracking of the RGB-D camera (paper §4.2, InfiniTAM's ICP tracker): the pose of
// a depth frame relative to a reference (ModelMaps, the TSDF's raycast or another frame) by
// point-to-plane ICP with projective data association, coarse to fine over a depth pyramid, with
// a photometric term where the geometry leaves a direction free; the conditioning of each solve;
// and whether the pose can be trusted (TrackingState).

#include <io/opencv.h>

#include "depth_pyramid.h"
#include "slam_types.h"

#include <camera/pinhole_camera.h>
#include <math/pose.h>

#include <array>
#include <memory>
#include <string>

namespace roomprobe {

class IcpReducerGpu;

struct IcpOptions {
	static constexpr int MAX_LEVELS = 4;
	int levels = 3; // pyramid levels used, 1..MAX_LEVELS; level l is 1 / 2^l of the full size
	// Gauss-Newton iterations per level, finest (0) first; a level stops early once an update moves
	// the pose by less than min_update_m and min_update_rad.
	std::array<int, MAX_LEVELS> iterations = { 10, 6, 8, 8 };
	double min_update_m = 1e-4; // metres
	double min_update_rad = 1e-4; // radians
	// The finest level pairs every finest_stride_px-th pixel of every finest_stride_px-th row (1:
	// all). Its depth is smoothed over a 5x5 window first (SurfaceOptions), so neighbouring pixels
	// carry nearly the same reading and a sample of them nearly the same information, for a
	// quarter of the work at 2; the model a frame is tracked against is coarser still (dense_slam.h
	// raycast_level).
	int finest_stride_px = 2;
	// The point-to-plane rows eight pixels at a time with AVX2 where the CPU has it
	// (icp_accumulate_simd.h: the same rows, summed in another order). false: the scalar kernel
	// everywhere, to compare with.
	bool simd = true;
	// Correspondences: point-to-point distance (metres) and angle between the normals (degrees)
	// beyond which a pair is an outlier. At the coarser levels the distance is allowed to grow by
	// coarse_distance_growth per level, for the larger initial error they have to take out.
	double max_distance_m = 0.1;
	double coarse_distance_growth = 2.0; // factor per level, >= 1
	double max_normal_angle_deg = 30.0;
	// Depth readings used, metres along z: real depth cameras (Kinect, RealSense, Azure Kinect) read
	// up to about 8 m. Far readings are noisier; their rows are weighted by depth_noise rather than
	// cut (on 7-Scenes: ATE 51 mm against 76 mm unweighted).
	double min_depth_m = 0.3, max_depth_m = 8.0;
	DepthNoiseModel depth_noise; // weights of far readings (slam_types.h)
	double pyramid_band_m = 0.05; // downsampling averages depths within this of a block's nearest, metres
	SurfaceOptions surface; // smoothing and normals of the frame
	// Photometric term: weight in metres per unit intensity (intensity in [0, 1], mean of R, G, B),
	// so that an intensity difference of 0.1 weighs as 0.1 * weight metres of point-to-plane
	// distance. 0: geometry only (the rgb image may then be empty).
	double colour_weight = 0.3;
	// false (default): the photometric rows join a level's solve only when its geometry leaves a
	// direction weakly constrained (see min_constraint): a flat wall, a floor, a corridor. Colour
	// and depth of real cameras are often not registered to the pixel (Kinect v1), and where the
	// geometry is enough, colour only adds that error and costs time. true: at every level.
	bool colour_always = false;
	double max_colour_difference = 0.1; // intensity (in [0, 1]) difference beyond which a pixel's colour row is an outlier
	// The colour slide guard. Along a direction the finest level's geometry leaves free, only the
	// colour term moves the pose away from the guess, and on a periodic or photo texture it can
	// lock onto the wrong match: the estimate stops or slides while every frame reads Good (issue
	// #41: the look-up sweep, level at a photographed wall, 1 -> 37 -> 55 mm in two frames). A
	// move from the guess along such directions larger than this is not believed: the pose keeps
	// the guess there, and the frame is Poor (TrackingResult::colour_held). A hand-held camera's
	// motion departs from constant velocity by a few millimetres a frame at 30 Hz: 15 mm and 1.5
	// degrees were measured (docs/FIGURES.md). Off by default (0 metres): on the two rooms' room
	// sweep it holds the slide by the wardrobe, and the room found from that sweep then has 12
	// corners, not 8 (issue #41).
	double max_colour_slide_m = 0.0; // metres; 0: no guard
	double max_colour_slide_deg = 1.5; // degrees

	// Tracking state.
	double min_valid_fraction = 0.05; // valid depth pixels / all, below: Lost
	int min_correspondences = 100; // inlier pairs at any level, below: Lost
	// Conditioning. Each solve's normal equations are scaled to be unit-free (the rotation and the
	// translation blocks to unit trace), so that a direction's eigenvalue is the share of the
	// frame's information that constrains it (a plane seen alone: about 1 along its normal, 0.5 for
	// each tilt, a noise floor of about 0.001 along it and about it). Directions below min_constraint are not updated
	// (their estimate stays at the initial guess), and a final pose with such a direction is Poor,
	// with a reason naming it ("flat geometry: translation along ... unconstrained").
	double min_constraint = 0.004;
	// Solves move only directions with at least this share (when above min_constraint; the state
	// still judges by min_constraint): DenseSlam raises it while its model is young
	// (DenseSlamOptions::young_model_noise_factor). 0: min_constraint.
	double hold_constraint = 0.0;
	double lost_inlier_fraction = 0.2; // inliers / valid depth pixels at the finest level, below: Lost
	double good_inlier_fraction = 0.5; // below (and not Lost): Poor
	double max_good_rmse_m = 0.02; // point-to-plane RMS of the inliers above which the pose is Poor, metres
	// Largest move from the initial guess that is believed (Lost beyond): a hand-held camera at
	// 30 Hz moves a few centimetres and degrees between frames.
	double max_jump_m = 0.25; // metres
	double max_jump_deg = 20.0; // degrees
};

class IcpTracker {
public:
	IcpTracker() = default;
	explicit IcpTracker(const IcpOptions &p_options) : options(p_options) {}

	const IcpOptions &get_options() const { return options; }
	void set_options(const IcpOptions &p_options) { options = p_options; }
	// The normal equations on a Vulkan device (icp_reduce_gpu.h), shared by copies of this tracker;
	// null: on the CPU. After a failed dispatch the tracker is back on the CPU, and
	// compute_problem() says why.
	void set_gpu(std::shared_ptr<IcpReducerGpu> p_gpu) { gpu = std::move(p_gpu); }
	bool uses_gpu() const;
	std::string compute_problem() const;

	// The pose of the camera that took p_depth_m (CV_32FC1, z metres, NaN or 0 = none; undistorted,
	// p_camera's size) and p_rgb (CV_8UC3 R, G, B; may be empty when colour_weight is 0) relative to
	// p_model, starting from p_initial_world_from_camera. When Lost, the result's pose is the initial
	// guess and reason says why.
	TrackingResult track(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const ModelMaps &p_model,
			const Pose &p_initial_world_from_camera) const;

private:
	IcpOptions options;
	std::shared_ptr<IcpReducerGpu> gpu;
};

// The reference a depth frame gives at a pose (frame-to-frame tracking, and tests without a
// TSDF): world points and normals of p_depth_m (CV_32FC1 metres, NaN or 0 = none; or CV_16UC1
// millimetres), smoothed and with normals as p_surface says, colours (p_rgb, CV_8UC3 R, G, B;
// zeros where there is no point or p_rgb is empty) and depth (the unsmoothed input, NaN = none),
// seen by p_camera at p_world_from_camera.
ModelMaps make_model_maps(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera,
		const SurfaceOptions &p_surface = SurfaceOptions());

// The angle of the rotation between two poses, degrees, and the distance between their
// positions, metres (how far an estimate is from another).
double rotation_difference_deg(const Pose &p_a, const Pose &p_b);
double translation_difference_m(const Pose &p_a, const Pose &p_b);

} // namespace roomprobe
