// RoomProbe's ICP tracker (extension/core/slam/icp_tracker.h) against OpenCV contrib's rgbd
// odometry (cv::rgbd::ICPOdometry, cv::rgbd::FastICPOdometry), frame-to-frame on the synthetic
// living room at 640x480 with Kinect-like depth noise: per-frame median time and ATE RMSE, in one
// process, so that the ratios mean something. Prints figures; asserts nothing.
//
// usage: build/bin/roomprobe_bench_tracking [frames=30] [passes=3] [rig=calib/synthetic_rig.yaml]

#include <io/opencv.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/rgbd.hpp>
#pragma GCC diagnostic pop

#include "camera/pinhole_camera.h"
#include "rig/rig.h"
#include "slam/icp_tracker.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

struct Frame {
	double time_s = 0.0;
	Pose truth; // world_from_camera
	cv::Mat depth_m; // CV_32FC1, NaN = none
	cv::Mat rgb; // CV_8UC3 R, G, B
	cv::Mat gray; // CV_8UC1, for OpenCV's odometry interface
	cv::Mat mask; // CV_8UC1, 255 where depth is valid
};

std::vector<Frame> render_frames(const synth::SynthRenderer &p_renderer, const synth::HandheldTrajectory &p_trajectory, const PinholeParams &p_camera,
		int p_count) {
	std::vector<Frame> frames;
	for (int i = 0; i < p_count; ++i) {
		Frame frame;
		frame.time_s = 2.0 + i / 30.0;
		frame.truth = p_trajectory.world_from_rgb(frame.time_s);
		synth::RgbdOptions options;
		options.noise_seed = synth::mix_seed(1, uint64_t(i));
		const synth::RgbdImage image = synth::render_rgbd(p_renderer, p_camera, 0.001, frame.truth, frame.time_s, options);
		image.depth.convertTo(frame.depth_m, CV_32FC1, 0.001);
		frame.mask = image.depth != 0;
		frame.depth_m.setTo(std::numeric_limits<float>::quiet_NaN(), ~frame.mask);
		frame.rgb = image.rgb;
		cv::cvtColor(image.rgb, frame.gray, cv::COLOR_RGB2GRAY);
		frames.push_back(frame);
	}
	return frames;
}

// One tracker: given the previous frame, its estimated pose and the current frame, the current
// estimate (false: it failed and the previous pose is held).
using TrackFunction = std::function<bool(const Frame &p_previous, const Pose &p_previous_pose, const Frame &p_current, Pose *r_pose)>;

struct Figures {
	double median_ms = 0.0;
	double ate_rmse_mm = 0.0;
	int failures = 0;
};

// Tracks the frames with every tracker, interleaved frame by frame so that a busy machine slows
// them alike; p_passes times over, the per-frame times of all passes pooled for the median.
std::vector<Figures> run(const std::vector<Frame> &p_frames, int p_passes, const std::vector<TrackFunction> &p_trackers) {
	const size_t n = p_trackers.size();
	std::vector<std::vector<double>> times_ms(n);
	std::vector<Figures> figures(n);
	for (int pass = 0; pass < p_passes; ++pass) {
		std::vector<Pose> poses(n, p_frames[0].truth);
		std::vector<double> sum_squared(n, 0.0);
		std::vector<int> failures(n, 0);
		for (size_t i = 1; i < p_frames.size(); ++i) {
			for (size_t k = 0; k < n; ++k) {
				Pose next = poses[k];
				const auto start = std::chrono::steady_clock::now();
				const bool ok = p_trackers[k](p_frames[i - 1], poses[k], p_frames[i], &next);
				times_ms[k].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
				failures[k] += ok ? 0 : 1;
				poses[k] = next;
				const double error = glm::length(next.translation - p_frames[i].truth.translation);
				sum_squared[k] += error * error;
			}
		}
		for (size_t k = 0; k < n; ++k) {
			figures[k].ate_rmse_mm = 1000.0 * std::sqrt(sum_squared[k] / double(p_frames.size() - 1));
			figures[k].failures = failures[k];
		}
	}
	for (size_t k = 0; k < n; ++k) {
		std::sort(times_ms[k].begin(), times_ms[k].end());
		figures[k].median_ms = times_ms[k][times_ms[k].size() / 2];
	}
	return figures;
}

Pose pose_of(const cv::Mat &p_rt) {
	glm::dmat4 m(1.0);
	for (int row = 0; row < 3; ++row) {
		for (int col = 0; col < 4; ++col) {
			m[col][row] = p_rt.at<double>(row, col);
		}
	}
	return pose_from_matrix(m);
}

// OpenCV's odometry: compute(src = current, dst = previous) gives Rt with dst_p = Rt src_p, that
// is previous_from_current.
TrackFunction opencv_tracker(const cv::Ptr<cv::rgbd::Odometry> &p_odometry) {
	return [p_odometry](const Frame &p_previous, const Pose &p_previous_pose, const Frame &p_current, Pose *r_pose) {
		cv::Mat rt;
		const bool ok = p_odometry->compute(p_current.gray, p_current.depth_m, p_current.mask, p_previous.gray, p_previous.depth_m, p_previous.mask, rt);
		if (ok) {
			*r_pose = compose(p_previous_pose, pose_of(rt));
		}
		return ok;
	};
}

TrackFunction roomprobe_tracker(const IcpOptions &p_options, const PinholeIntrinsics &p_camera) {
	return [p_options, p_camera](const Frame &p_previous, const Pose &p_previous_pose, const Frame &p_current, Pose *r_pose) {
		const ModelMaps model = make_model_maps(p_previous.depth_m, p_options.colour_weight != 0.0 ? p_previous.rgb : cv::Mat(), p_camera,
				p_previous_pose, p_options.surface);
		const TrackingResult result = IcpTracker(p_options).track(p_current.depth_m, p_current.rgb, p_camera, model, p_previous_pose);
		*r_pose = result.world_from_camera;
		return result.state != TrackingState::Lost;
	};
}

// Where RoomProbe's time goes: make_model_maps and track apart, and the iterations.
void print_breakdown(const std::vector<Frame> &p_frames, const IcpOptions &p_options, const PinholeIntrinsics &p_camera) {
	std::vector<double> maps_ms, track_ms;
	double iterations = 0.0;
	for (size_t i = 1; i < p_frames.size(); ++i) {
		auto start = std::chrono::steady_clock::now();
		const ModelMaps model = make_model_maps(p_frames[i - 1].depth_m, cv::Mat(), p_camera, p_frames[i - 1].truth, p_options.surface);
		maps_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
		start = std::chrono::steady_clock::now();
		const TrackingResult result = IcpTracker(p_options).track(p_frames[i].depth_m, cv::Mat(), p_camera, model, p_frames[i - 1].truth);
		track_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
		iterations += result.iterations;
	}
	std::sort(maps_ms.begin(), maps_ms.end());
	std::sort(track_ms.begin(), track_ms.end());
	std::printf("  RoomProbe breakdown: make_model_maps %.2f ms, track %.2f ms (median), %.1f Gauss-Newton iterations a frame\n",
			maps_ms[maps_ms.size() / 2], track_ms[track_ms.size() / 2], iterations / double(p_frames.size() - 1));
}

void print(const char *p_name, const Figures &p_figures, const Figures &p_reference) {
	std::printf("  %-44s %8.2f ms  (x%5.2f)   ATE RMSE %7.2f mm   failed frames %d\n", p_name, p_figures.median_ms,
			p_figures.median_ms / p_reference.median_ms, p_figures.ate_rmse_mm, p_figures.failures);
}

} // namespace

int main(int p_argc, char **p_argv) {
	const int count = p_argc > 1 ? std::max(2, std::atoi(p_argv[1])) : 30;
	const int passes = p_argc > 2 ? std::max(1, std::atoi(p_argv[2])) : 3;
	const synth::SceneResult scene = synth::make_scene("living_room", synth::SceneOptions());
	if (!scene.ok) {
		std::fprintf(stderr, "scene: %s\n", scene.error.c_str());
		return 1;
	}
	const synth::SynthRenderer renderer(scene.scene);
	if (!renderer.ok()) {
		std::fprintf(stderr, "renderer: %s\n", renderer.error().c_str());
		return 1;
	}
	// The synthetic rig's RGB-D camera (640x480, fx = fy = 525); run from the repository root.
	const char *rig_path = p_argc > 3 ? p_argv[3] : "calib/synthetic_rig.yaml";
	const RigLoadResult rig = load_rig(rig_path);
	if (!rig.ok) {
		std::fprintf(stderr, "%s\n", rig.error.c_str());
		return 1;
	}
	const PinholeParams camera = rig.rig.rgb;
	const std::vector<Frame> frames = render_frames(renderer, synth::make_handheld_trajectory(scene.scene, 1), camera, count);
	std::printf("living_room, %d frames at 640x480 (30 Hz, noisy depth), frame-to-frame, %d passes, %d OpenCV threads\n", count, passes,
			cv::getNumThreads());
	double path_m = 0.0;
	for (size_t i = 1; i < frames.size(); ++i) {
		path_m += glm::length(frames[i].truth.translation - frames[i - 1].truth.translation);
	}
	std::printf("  ground-truth path: %.1f mm\n", path_m * 1000.0);

	const PinholeIntrinsics intrinsics = pinhole_intrinsics(camera);
	const cv::Mat k = (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
	IcpOptions ours;
	IcpOptions ours_colour = ours;
	ours_colour.colour_weight = 0.1;
	// OpenCV's defaults, with our depth range.
	const float min_depth = float(ours.min_depth_m), max_depth = float(ours.max_depth_m);
	const std::vector<Figures> figures = run(frames, passes,
			{ roomprobe_tracker(ours, intrinsics), roomprobe_tracker(ours_colour, intrinsics),
					opencv_tracker(cv::rgbd::ICPOdometry::create(k, min_depth, max_depth)), opencv_tracker(cv::rgbd::FastICPOdometry::create(k)) });
	const Figures &icp = figures[0], &icp_colour = figures[1], &cv_icp = figures[2], &cv_fast = figures[3];

	std::printf("per-frame median time (ratio to RoomProbe IcpTracker), ATE RMSE of translation:\n");
	print("RoomProbe IcpTracker (make_model_maps+track)", icp, icp);
	print("RoomProbe IcpTracker, colour weight 0.1", icp_colour, icp);
	print("cv::rgbd::ICPOdometry", cv_icp, icp);
	print("cv::rgbd::FastICPOdometry", cv_fast, icp);
	print_breakdown(frames, ours, intrinsics);
	return 0;
}
