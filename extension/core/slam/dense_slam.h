#pragma once
// Dense RGB-D SLAM (paper §4.2) as one plain C++ object: the colour TSDF of the surfaces near the
// virtual objects (tsdf_volume.h) and the RGB-D camera's pose, frame-to-model ICP (icp_tracker.h)
// against the model's raycast from the last pose. Open3D's slam Model, four verbs:
//   track      the pose of a frame, against the model seen from the last trusted pose;
//   integrate  fuse a frame at a pose;
//   raycast    the model seen from a pose (the next frame's reference);
//   mesh       marching cubes of what changed (marching_cubes.h), for Godot and Embree;
// and process(), which runs a frame through them in order.
//
// Tracking states (slam_types.h): Good frames are integrated; Poor ones move the pose but are not
// integrated (unless integrate_poor), except those Poor only for a direction nothing constrains
// (integrate_unconstrained); when Lost the last trusted pose is held, nothing is
// integrated, and each new frame tries to re-track against the model from that pose and, failing
// that, relocalises: a wider search from starting poses around it (DenseSlamOptions), so that
// tracking resumes when the camera comes back near where it was lost, then the keyframes
// (keyframes.h) that look most like the frame, each verified by ICP against the model seen from
// it, so that a camera carried anywhere the sweep has been is found again (issue #41). A pose
// the searches cannot explain stays Lost.
//
// World frame: the caller's, through the initial pose (a recording's room.yaml initial_rgb_pose
// puts the dense model in the room's frame, where the coarse model is).

#include "icp_tracker.h"
#include "keyframes.h"
#include "marching_cubes.h"
#include "slam_types.h"
#include "tsdf_volume.h"

#include <camera/camera_params.h>
#include <gpu/compute_device.h>
#include <types/frames.h>

#include <atomic>
#include <memory>
#include <shared_mutex>
#include <string>

namespace roomprobe {

struct DenseSlamOptions {
	DenseSlamOptions() {
		// Against the model rather than the last frame: the model covers less than a frame sees
		// at first (grazing surfaces and depth edges are not fused, tsdf_volume.h), so a smaller
		// share of the frame's pixels find a partner while tracking is still sound.
		icp.good_inlier_fraction = 0.3;
	}
	TsdfOptions tsdf; // the volume: voxel size, truncation, block cap (units there)
	IcpOptions icp; // tracking: pyramid, thresholds, colour term (units there)
	bool integrate_poor = false; // also fuse frames whose tracking is Poor
	// Fuse the frames that are Poor only because a direction is unconstrained (TrackingResult::
	// unconstrained: a bare corner, two parallel striped planes), at their pose, whose free
	// direction the finest level left at the guess. Their error along it (the rig's real motion
	// that way, a few centimetres over a second) goes into the model, but the model keeps growing
	// while the camera turns, and tracking goes on once the view has structure again. Unfused, the
	// model stopped where the view went flat, the camera turned past it, and the rest of the sweep
	// was lost (issue #18: panorama_room's room sweep, a bare corner 2 s in, then 188 of 300
	// frames lost; fused, 1).
	bool integrate_unconstrained = true;
	bool constant_velocity = true; // predict each pose from the last two trusted ones (else: the last one)
	// A hand-held rig moves slower than this. A pose that moved faster since the last tracked one
	// (plus 2 cm for noise) slid along surfaces that do not fix it (a bare wall and its corner),
	// and is Lost, not Good: else the constant-velocity guess carries the slide on, frame after
	// frame (issue #18's room sweep: 9 m off in a second, every frame "good").
	double max_speed_m_s = 3.0;
	// The tracking reference is raycast at 1 / 2^raycast_level of the camera's size (160x120 from
	// 640x480 at 2): ICP's projective association reads the model at any size, and a quarter-size
	// reference cost 8 ms instead of 60 with the same ATE (1.3 mm on out/demo/recording). 0: full.
	int raycast_level = 2;
	// The reference is searched only within this distance (camera z, metres) of the readings of
	// the frame just fused at that pixel (their min and max over the reference pixel's block):
	// the model there was just made to agree with them, and the rays need not march the empty
	// room in front. Pixels without readings search the whole range. 0: every pixel the whole range.
	float reference_search_margin_m = 0.08f;
	// The reference's normals from its neighbouring points (KinectFusion's model normals, made as
	// the frame's are: model_normals_from_points), not from the tsdf's gradient at each hit (six
	// trilinear reads a ray). Measured (docs/FIGURES.md): the two rooms 4.35 -> 4.06 mm ATE, the
	// 10-s living room 4.53 -> 4.19, the 20-s one 11.51 -> 11.04, 7-Scenes 44.32 -> 44.43, the
	// reference raycast 8-13 % faster. Not the default yet: the two rooms' room sweep, which loses
	// the camera either way, then ends elsewhere and its room has 14 corners, not 8 (issue #41).
	bool reference_normals_from_points = false;
	// A young model holds its free directions harder (opt-in). While fewer than
	// young_model_frames frames are fused, a direction needs young_model_noise_factor times the
	// reference's normal spread (normal_spread, depth_pyramid.h) of the information before a solve
	// moves it (IcpOptions::hold_constraint; the tracking state still judges by min_constraint):
	// a model of one or two noisy frames gives a free direction a share of the information from its
	// normals' noise alone (0.17 on the panorama room's first frame, seen from 2.5 m), and the
	// first solves slid the camera 0.7 m along a bare wall. Measured at 15 frames and 0.25
	// (docs/FIGURES.md, issue #41): the panorama room 680 -> 46 mm ATE, the living room 4.53 ->
	// 4.01 mm, the two rooms 4.35 -> 4.14, the 20-s living room 11.51 -> 11.68, 7-Scenes 44.32 ->
	// 46.33; but the evaluation's short living-room sweep (core test `eval: on living_room ...`)
	// then drifts to 123 mm, so it is off. 0 frames or a factor of 0: off.
	int young_model_frames = 0;
	double young_model_noise_factor = 0.25;
	// Tracking runs on the frame at 1 / 2^tracking_level of its size (ICP's own pyramid below
	// that); integration always takes the full frame. 0, the default: full size. Level 1 tracks
	// 2.5x faster (14 to 18 ms against 37 on the 10-s living room) without the drift once seen,
	// but costs ATE: 1.70 -> 5.61 mm on the flat-wall panorama_room, 4.43 -> 5.05 on living_room,
	// 44.4 -> 47.2 mm on 7-Scenes (docs/FIGURES.md, speed on two CPU cores), so it is not the default.
	int tracking_level = 0;
	// Relocalisation: when a frame is Lost and the model exists, it is tracked again from 13
	// starting poses: the held pose, and the held pose moved by +-relocalise_step_m along each
	// camera axis and turned by +-relocalise_step_deg about each. The best Good result (most
	// inliers) is refined once more from there, and taken only if it is Good and within
	// relocalise_max_m and relocalise_max_deg of the held pose. About 13 coarse ICP solves per
	// lost frame (a few tens of ms at 640x480), only while lost.
	bool relocalise = true;
	// When that finds nothing, the keyframes (keyframes.h) whose thumbnails are nearest the lost
	// frame's are tried, relocalise_keyframes of them: each is verified by tracking the frame
	// against the model raycast from the keyframe's pose (the coarse levels, within
	// relocalise_max_m and _deg of it), then again at full resolution against the model seen from
	// the pose found. Only a Good result of both is taken ("relocalised at keyframe K"), wherever
	// it is: the camera may have been carried anywhere while lost, so max_speed_m_s does not apply
	// to it. That frame stays Lost; the next, tracked from the pose found, confirms it (Good, and
	// within max_speed_m_s of it), so a slide along a bare wall would have to repeat itself.
	bool relocalise_globally = true;
	int relocalise_keyframes = 3;
	KeyframeOptions keyframes;
	double relocalise_step_m = 0.1; // metres
	double relocalise_step_deg = 10.0; // degrees
	double relocalise_max_m = 0.35; // metres from the held pose
	double relocalise_max_deg = 25.0; // degrees from the held pose
};

// Wall-clock milliseconds of one process() call, by stage.
struct DenseSlamTimings {
	double undistort_ms = 0.0;
	double track_ms = 0.0;
	double integrate_ms = 0.0;
	double raycast_ms = 0.0;
	double frame_ms = 0.0; // the whole call
};

struct DenseSlamFrame {
	TrackingResult tracking; // state, reason, pose (the held pose when Lost)
	bool integrated = false;
	IntegrationStats integration;
	DenseSlamTimings timings;
};

class DenseSlam {
public:
	explicit DenseSlam(const DenseSlamOptions &p_options = DenseSlamOptions());

	// Sets the RGB-D camera (depth registered to it; distortion is undone per frame) and the pose
	// of the first frame, and empties the model. The error (empty on success) names the problem.
	std::string configure(const PinholeParams &p_camera, const Pose &p_initial_world_from_camera);
	bool is_configured() const { return configured; }
	// Where tracking's pyramid and normal equations are made and where voxels are fused (issue
	// #40): on p_device (icp_reduce_gpu.h, tsdf_integrate_gpu.h), or on the CPU when it is null.
	// "" or what stays on the CPU and why ("tracking on the CPU (...)", "integration on the CPU (...)").
	std::string set_compute(std::shared_ptr<ComputeDevice> p_device);
	// Whether tracking and integration run on a device now, and, when set_compute's device
	// refused a kernel or a dispatch failed and put a stage back on the CPU, which and why, in
	// set_compute's words ("" otherwise).
	bool tracks_on_gpu() const { return tracker.uses_gpu(); }
	bool integrates_on_gpu() const { return tsdf.integrates_on_gpu(); }
	std::string compute_problem() const;

	// The four verbs, on undistorted images (p_depth_m CV_32FC1 z metres, NaN or 0 = none;
	// p_rgb CV_8UC3 R, G, B, same size).
	TrackingResult track(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_initial_world_from_camera) const;
	IntegrationStats integrate(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_world_from_camera);
	void raycast(const Pose &p_world_from_camera, ModelMaps *r_maps) const;
	// The blocks changed since the last call, with the voxels re-meshing them reads, copied: an
	// IncrementalMesher fed these copies in order keeps the model's mesh, on any thread. Call it
	// on the fusing thread (a copy of the order of 100 MB takes tens of milliseconds; meshing it
	// takes ten times that).
	// p_storage: an earlier copy's storage to reuse (TsdfBlockCopy::release_storage), or empty.
	TsdfBlockCopy copy_changed_blocks(std::vector<TsdfVoxel> p_storage = {});

	// One RGB-D frame: undistort, track (the first frame is taken at the initial pose), integrate
	// when trusted, raycast the reference for the next frame.
	DenseSlamFrame process(const RgbdFrame &p_frame);
	// The same without tracking: the frame is fused at p_world_from_camera (ground-truth poses,
	// the evaluation mode), and that becomes the pose.
	DenseSlamFrame process_at_pose(const RgbdFrame &p_frame, const Pose &p_world_from_camera);

	// The RGB-D camera's pose (world_from_camera) after the last frame (held while Lost), and its state.
	const Pose &pose() const { return last_pose; }
	TrackingState state() const { return last_state; }
	size_t frame_count() const { return frames; }
	size_t integrated_count() const { return integrated_frames; }
	// Lost frames the relocalisation search ran on, and those it recovered (Good again).
	size_t relocalisation_attempts() const { return relocalise_attempts; }
	size_t relocalisation_count() const { return relocalised_frames; }
	// Keyframes kept so far, and the relocalisations that came from one (a subset of the above).
	size_t keyframe_count() const { return keyframe_total; }
	size_t keyframe_relocalisation_count() const { return keyframe_relocalised; }
	const TsdfVolume &volume() const { return tsdf; }
	TsdfVolume &volume() { return tsdf; }
	// For readers on other threads (a probe's dense pass): while held, no frame is being fused, so
	// the volume is whole. Fusing (integrate, process, process_at_pose) takes the lock exclusively
	// and only for the fusing itself; tracking and meshing only read, on the fusing thread.
	std::shared_lock<std::shared_mutex> read_lock() const { return std::shared_lock<std::shared_mutex>(volume_mutex); }
	const PinholeIntrinsics &camera() const { return intrinsics; }
	const DenseSlamOptions &options() const { return opts; }

private:
	void undistort(const RgbdFrame &p_frame, cv::Mat *r_depth, cv::Mat *r_rgb) const;
	TrackingResult track_with(const IcpTracker &p_tracker, const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_initial_world_from_camera) const;
	// The tracker both relocalisation searches solve candidates with: the coarse levels only, with
	// the search's jump limits (relocalise_max_m, _deg).
	IcpTracker search_tracker() const;
	// The wider search after a loss, around the held pose (see DenseSlamOptions::relocalise).
	TrackingResult relocalise(const cv::Mat &p_depth_m, const cv::Mat &p_rgb) const;
	// The search over the keyframes (DenseSlamOptions::relocalise_globally): Good with the pose
	// and r_keyframe's id when one verified.
	TrackingResult relocalise_at_keyframes(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, int *r_keyframe) const;
	// That search with its confirmation: a pose found is held as the candidate and the frame stays
	// Lost; the next lost frame, tracked from the candidate, confirms it (Good) or not.
	TrackingResult relocalise_far(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, double p_time_s);
	// p_tracker's result for the frame against p_model (at the tracking level, as track_with).
	TrackingResult track_against(const IcpTracker &p_tracker, const ModelMaps &p_model, const cv::Mat &p_depth_m, const cv::Mat &p_rgb,
			const Pose &p_initial_world_from_camera) const;
	// The model seen from p_pose as the reference is (raycast_level, no search intervals).
	ModelMaps reference_at(const Pose &p_pose) const;
	// The tracking reference from p_pose into r_maps, within p_search_m's intervals when given,
	// its normals as reference_normals_from_points asks (reference_at and process share it).
	void cast_reference(const Pose &p_pose, const cv::Mat *p_search_m, ModelMaps *r_maps) const;
	// Empty when p_frame fits the camera, else why not.
	std::string check_frame(const RgbdFrame &p_frame) const;
	// Empty when p_tracking's pose at p_time_s is within max_speed_m_s of the last tracked one, else why not.
	std::string faster_than_a_hand(const TrackingResult &p_tracking, double p_time_s) const;
	// The same from another pose at another time (a relocalisation's candidate).
	std::string faster_than_a_hand(const TrackingResult &p_tracking, double p_time_s, const Pose &p_from, double p_from_time_s) const;

	DenseSlamOptions opts;
	bool configured = false;
	PinholeParams params;
	PinholeIntrinsics intrinsics;
	cv::Mat undistort_map_x, undistort_map_y; // empty when the camera has no distortion
	IcpTracker tracker;
	std::string compute_error; // set_compute's
	TsdfVolume tsdf;
	ModelMaps reference; // the model raycast from last_pose
	KeyframeDatabase keyframes; // trusted frames far apart, for relocalisation from anywhere
	struct KeyframeCandidate {
		bool pending = false;
		Pose pose; // found at a keyframe, for the next frame to confirm
		double time_s = 0.0;
		int keyframe = -1;
	};
	KeyframeCandidate candidate;
	Pose last_pose;
	Pose previous_pose; // the trusted pose before last_pose (constant-velocity prediction)
	double last_time_s = 0.0, previous_time_s = 0.0; // their frames' timestamps
	bool has_previous = false;
	TrackingState last_state = TrackingState::Lost;
	bool last_colour_held = false; // the last frame's TrackingResult::colour_held
	// Atomic: read by other threads (the engine's stats, the dense lighting of probes).
	std::atomic<size_t> frames = 0;
	std::atomic<size_t> integrated_frames = 0;
	std::atomic<size_t> relocalise_attempts = 0;
	std::atomic<size_t> relocalised_frames = 0;
	std::atomic<size_t> keyframe_total = 0;
	std::atomic<size_t> keyframe_relocalised = 0;
	mutable std::shared_mutex volume_mutex;
};

} // namespace roomprobe
