// RoomProbe's ICP tracker (extension/core/slam/icp_tracker.h) against OpenCV contrib's rgbd
// odometry (cv::rgbd::ICPOdometry, cv::rgbd::FastICPOdometry), all frame-to-frame: each tracker
// estimates the motion from the previous frame to the current one and chains it onto its own
// previous estimate (the full pose chain, as a visual odometry runs), from the ground truth's pose
// of the first frame. Per-frame median time, ATE RMSE and RPE (eval/trajectory_metrics.h: no
// alignment, the same convention as roomprobe_bench), in one process, so that the ratios mean
// something. Prints figures; asserts nothing.
//
// Synthetic (no option): the living room at 640x480 with Kinect-like depth noise, rendered here.
// Dataset (--7scenes DIR or --tum DIR): real frames through the readers (recording/
// frames_dataset.h, recording/tum_dataset.h), undistorted first when the camera has distortion;
// ends with one line 'summary: mode=tracking ... key=value ...'.
//
// usage: build/bin/roomprobe_bench_tracking [frames=30, 2 to 1000] [passes=3, 1 to 100] [rig=calib/synthetic_rig.yaml]
//        build/bin/roomprobe_bench_tracking (--7scenes DIR | --tum DIR) [--frames N, 1 to 100000] [--passes N, 1 to 100]

#include <io/opencv.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/rgbd.hpp>
#pragma GCC diagnostic pop

#include "../common/cli.h"

#include "camera/pinhole_camera.h"
#include "eval/trajectory_metrics.h"
#include "recording/frames_dataset.h"
#include "recording/tum_dataset.h"
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
	bool has_truth = true; // false: the ground truth has no pose at this frame
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
	AbsoluteTrajectoryError ate;
	RelativePoseError rpe; // per frame
	int failures = 0;
};

// Tracks the frames with every tracker, interleaved frame by frame so that a busy machine slows
// them alike; p_passes times over, the per-frame times of all passes pooled for the median. Each
// starts at frame 0's true pose; the accuracy is the last pass's.
std::vector<Figures> run(const std::vector<Frame> &p_frames, int p_passes, const std::vector<TrackFunction> &p_trackers) {
	const size_t n = p_trackers.size();
	std::vector<std::vector<double>> times_ms(n);
	std::vector<Figures> figures(n);
	Trajectory truth;
	std::vector<TimedPose> true_samples;
	for (const Frame &frame : p_frames) {
		if (frame.has_truth) {
			true_samples.push_back({ frame.time_s, frame.truth });
		}
	}
	std::string error;
	if (!truth.set_samples(std::move(true_samples), &error)) {
		std::fprintf(stderr, "ground truth: %s\n", error.c_str());
	}
	for (int pass = 0; pass < p_passes; ++pass) {
		std::vector<Pose> poses(n, p_frames[0].truth);
		std::vector<std::vector<TimedPose>> estimates(n, std::vector<TimedPose>{ { p_frames[0].time_s, p_frames[0].truth } });
		std::vector<int> failures(n, 0);
		for (size_t i = 1; i < p_frames.size(); ++i) {
			for (size_t k = 0; k < n; ++k) {
				Pose next = poses[k];
				const auto start = std::chrono::steady_clock::now();
				const bool ok = p_trackers[k](p_frames[i - 1], poses[k], p_frames[i], &next);
				times_ms[k].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
				failures[k] += ok ? 0 : 1;
				poses[k] = next;
				estimates[k].push_back({ p_frames[i].time_s, next });
			}
		}
		for (size_t k = 0; k < n; ++k) {
			Trajectory estimate;
			if (!estimate.set_samples(std::move(estimates[k]), &error)) {
				std::fprintf(stderr, "tracker %zu: %s\n", k, error.c_str());
			}
			figures[k].ate = absolute_trajectory_error(estimate, truth);
			figures[k].rpe = relative_pose_error(estimate, truth, 1.0, RpeDelta::Frames);
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
	std::printf("  %-44s %8.2f ms  (x%5.2f)   ATE RMSE %8.2f mm   RPE/frame %6.2f mm %6.3f deg   failed frames %d\n", p_name, p_figures.median_ms,
			p_figures.median_ms / p_reference.median_ms, 1000.0 * p_figures.ate.rmse_m, 1000.0 * p_figures.rpe.translation_rmse_m,
			p_figures.rpe.rotation_rmse_deg, p_figures.failures);
}

// The four trackers on the same frames, as both modes run them.
struct Comparison {
	std::vector<Figures> figures; // ours (defaults), ours with colour at every level, ICPOdometry, FastICPOdometry
	static constexpr const char *KEYS[4] = { "ours", "ours_colour", "cv_icp", "cv_fast_icp" };
};

Comparison compare(const std::vector<Frame> &p_frames, int p_passes, const PinholeParams &p_camera) {
	const PinholeIntrinsics intrinsics = pinhole_intrinsics(p_camera);
	const cv::Mat k = (cv::Mat_<double>(3, 3) << p_camera.fx, 0.0, p_camera.cx, 0.0, p_camera.fy, p_camera.cy, 0.0, 0.0, 1.0);
	IcpOptions ours; // the defaults: colour only where the geometry leaves a direction free
	IcpOptions ours_colour = ours;
	ours_colour.colour_always = true;
	// OpenCV's defaults, with our depth range.
	const float min_depth = float(ours.min_depth_m), max_depth = float(ours.max_depth_m);
	Comparison comparison;
	comparison.figures = run(p_frames, p_passes,
			{ roomprobe_tracker(ours, intrinsics), roomprobe_tracker(ours_colour, intrinsics),
					opencv_tracker(cv::rgbd::ICPOdometry::create(k, min_depth, max_depth)), opencv_tracker(cv::rgbd::FastICPOdometry::create(k)) });
	const std::vector<Figures> &f = comparison.figures;
	std::printf("per-frame median time (ratio to RoomProbe IcpTracker), ATE RMSE of translation, RPE per frame (translation, rotation):\n");
	print("RoomProbe IcpTracker (make_model_maps+track)", f[0], f[0]);
	print("RoomProbe IcpTracker, colour at every level", f[1], f[0]);
	print("cv::rgbd::ICPOdometry", f[2], f[0]);
	print("cv::rgbd::FastICPOdometry", f[3], f[0]);
	print_breakdown(p_frames, ours, intrinsics);
	return comparison;
}

// --7scenes DIR or --tum DIR: the frames through the reader, undistorted when the camera has
// distortion (the trackers take pinhole images), from the first frame the ground truth covers.
bool load_dataset(const std::string &p_kind, const std::string &p_folder, long p_max_frames, std::vector<Frame> *r_frames, PinholeParams *r_camera) {
	RecordingReader reader;
	RecordingStatus status;
	if (p_kind == "7scenes") {
		status = open_frames_dataset(p_folder, &reader);
	} else {
		TumDatasetOptions options;
		TumCamera camera = TumCamera::RosDefault;
		tum_camera_from_folder_name(p_folder, &camera);
		options.rgb = tum_camera_intrinsics(camera);
		status = open_tum_dataset(p_folder, &reader, options);
	}
	if (!status.ok) {
		std::fprintf(stderr, "--%s: %s\n", p_kind.c_str(), status.error.c_str());
		return false;
	}
	for (const RecordingIssue &issue : reader.get_issues()) {
		std::printf("  issue: %s\n", to_string(issue).c_str());
	}
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	if (truth.is_empty()) {
		std::fprintf(stderr, "--%s %s: no ground-truth trajectory, so no start pose and no accuracy\n", p_kind.c_str(), p_folder.c_str());
		return false;
	}
	PinholeParams camera = reader.get_rig().rgb;
	cv::Mat map_x, map_y;
	if (has_pinhole_distortion(camera)) {
		const cv::Mat k = (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
		const cv::Mat d = (cv::Mat_<double>(1, 5) << camera.k1, camera.k2, camera.p1, camera.p2, camera.k3);
		cv::initUndistortRectifyMap(k, d, cv::Mat(), k, cv::Size(camera.width, camera.height), CV_32FC1, map_x, map_y);
		camera.k1 = camera.k2 = camera.p1 = camera.p2 = camera.k3 = 0.0;
	}
	r_frames->clear();
	for (size_t i = 0; i < reader.rgbd_count() && (p_max_frames <= 0 || long(r_frames->size()) < p_max_frames); i++) {
		RgbdFrameResult read = reader.read_rgbd(i);
		if (!read.ok) {
			std::fprintf(stderr, "%s (frame skipped)\n", read.error.c_str());
			continue;
		}
		Frame frame;
		frame.time_s = read.frame.timestamp_s;
		std::string error;
		frame.has_truth = truth.pose_at(frame.time_s, &frame.truth, &error);
		if (r_frames->empty() && !frame.has_truth) {
			continue; // start where the ground truth does
		}
		frame.depth_m = read.frame.depth_m;
		frame.rgb = read.frame.rgb;
		if (!map_x.empty()) {
			cv::remap(read.frame.depth_m, frame.depth_m, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
			cv::remap(read.frame.rgb, frame.rgb, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
		}
		frame.mask = frame.depth_m == frame.depth_m; // not NaN
		cv::cvtColor(frame.rgb, frame.gray, cv::COLOR_RGB2GRAY);
		r_frames->push_back(frame);
	}
	if (r_frames->size() < 2) {
		std::fprintf(stderr, "--%s %s: fewer than 2 usable frames with a ground-truth start\n", p_kind.c_str(), p_folder.c_str());
		return false;
	}
	*r_camera = camera;
	return true;
}

// The bounds of the counts (issue #38): every frame is held in memory (about 2 MB at 640x480), and
// every pass runs each tracker over all of them.
constexpr long MAX_SYNTH_FRAMES = 1000, MAX_DATASET_FRAMES = 100000, MAX_PASSES = 100;

// Positional argument p_index as a whole number in [p_min, p_max] into *r_value (left as it is when
// absent); false, saying so, otherwise.
bool positional(int p_argc, char **p_argv, int p_index, const char *p_name, long p_min, long p_max, long *r_value) {
	if (p_index >= p_argc) {
		return true;
	}
	long n = 0;
	if (!cli::parse_integer(p_argv[p_index], &n) || n < p_min || n > p_max) {
		std::fprintf(stderr, "%s needs a whole number in %s, got '%s'\n", p_name, cli::range_text(double(p_min), double(p_max)).c_str(), p_argv[p_index]);
		return false;
	}
	*r_value = n;
	return true;
}

int run_dataset(int p_argc, char **p_argv) {
	std::string kind, folder;
	long frames = 0, passes = 1;
	cli::Arguments cursor(p_argc, p_argv, 1);
	std::string arg;
	while (cursor.next(&arg)) {
		if (arg == "--7scenes" || arg == "--tum") {
			if (!kind.empty()) {
				std::fprintf(stderr, "--7scenes and --tum each name a dataset: give one\n");
				return 2;
			}
			kind = arg.substr(2);
			if (!cursor.value(&folder)) {
				std::fprintf(stderr, "%s needs a folder\n", arg.c_str());
				return 2;
			}
		} else if (arg == "--frames" || arg == "--passes") {
			const long most = arg == "--frames" ? MAX_DATASET_FRAMES : MAX_PASSES;
			if (!cursor.integer_in(1, most, arg == "--frames" ? &frames : &passes)) {
				std::fprintf(stderr, "%s needs a whole number in %s\n", arg.c_str(), cli::range_text(1, double(most)).c_str());
				return 2;
			}
		} else {
			std::fprintf(stderr, "unknown argument %s\nusage: roomprobe_bench_tracking (--7scenes DIR | --tum DIR) [--frames N] [--passes N]\n", arg.c_str());
			return 2;
		}
	}
	if (kind.empty()) {
		std::fprintf(stderr, "usage: roomprobe_bench_tracking (--7scenes DIR | --tum DIR) [--frames N] [--passes N]\n");
		return 2;
	}
	std::printf("roomprobe_bench_tracking --%s %s\n", kind.c_str(), folder.c_str());
	std::vector<Frame> loaded;
	PinholeParams camera;
	if (!load_dataset(kind, folder, frames, &loaded, &camera)) {
		return 1;
	}
	double path_m = 0.0;
	for (size_t i = 1; i < loaded.size(); ++i) {
		path_m += glm::length(loaded[i].truth.translation - loaded[i - 1].truth.translation);
	}
	std::printf("  %zu frames %dx%d from t = %.3f s, frame-to-frame, %ld passes, %d OpenCV threads; fx %.2f fy %.2f cx %.2f cy %.2f\n", loaded.size(),
			camera.width, camera.height, loaded[0].time_s, passes, cv::getNumThreads(), camera.fx, camera.fy, camera.cx, camera.cy);
	std::printf("  ground-truth path: %.1f mm; accuracy against the ground truth, from its pose of the first frame, no alignment\n", path_m * 1000.0);
	const Comparison comparison = compare(loaded, int(passes), camera);
	std::string summary = "summary: mode=tracking source=" + kind + " frames=" + std::to_string(loaded.size());
	for (size_t k = 0; k < comparison.figures.size(); k++) {
		const Figures &f = comparison.figures[k];
		char text[256];
		std::snprintf(text, sizeof(text), " %s_ms_p50=%.2f %s_ate_mm=%.2f %s_rpe_mm=%.2f %s_rpe_deg=%.3f %s_failed=%d", Comparison::KEYS[k], f.median_ms,
				Comparison::KEYS[k], 1000.0 * f.ate.rmse_m, Comparison::KEYS[k], 1000.0 * f.rpe.translation_rmse_m, Comparison::KEYS[k],
				f.rpe.rotation_rmse_deg, Comparison::KEYS[k], f.failures);
		summary += text;
	}
	std::printf("%s\n", summary.c_str());
	return 0;
}

int run(int p_argc, char **p_argv) {
	if (p_argc > 1 && std::string(p_argv[1]).rfind("--", 0) == 0) {
		return run_dataset(p_argc, p_argv);
	}
	long count = 30, passes = 3;
	if (!positional(p_argc, p_argv, 1, "frames", 2, MAX_SYNTH_FRAMES, &count) || !positional(p_argc, p_argv, 2, "passes", 1, MAX_PASSES, &passes)) {
		return 2;
	}
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
	const std::vector<Frame> frames = render_frames(renderer, synth::make_handheld_trajectory(scene.scene, 1), camera, int(count));
	std::printf("living_room, %ld frames at 640x480 (30 Hz, noisy depth), frame-to-frame, %ld passes, %d OpenCV threads\n", count, passes,
			cv::getNumThreads());
	double path_m = 0.0;
	for (size_t i = 1; i < frames.size(); ++i) {
		path_m += glm::length(frames[i].truth.translation - frames[i - 1].truth.translation);
	}
	std::printf("  ground-truth path: %.1f mm\n", path_m * 1000.0);

	compare(frames, int(passes), camera);
	return 0;
}

} // namespace

int main(int p_argc, char **p_argv) {
	return roomprobe::cli::guarded_main("roomprobe_bench_tracking", [&] { return run(p_argc, p_argv); });
}
