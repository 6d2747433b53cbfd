#pragma once
// roomprobe_bench's shared parts (bench_main.cpp says what each benchmark measures): the command
// line's settings, the per-frame series and their table rows, dense SLAM's figures, the tracked
// trajectory's file and its accuracy, and the benchmarks' entry points.

#include <engine/live_room.h>
#include <eval/trajectory_metrics.h>
#include <recording/recording_reader.h>
#include <rig/trajectory.h>
#include <slam/dense_slam.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace roomprobe::bench {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

inline double ms_between(Clock::time_point p_from, Clock::time_point p_to) {
	return std::chrono::duration<double, std::milli>(p_to - p_from).count();
}

// As the live nodes: DenseSLAM's mesh_update_interval.
constexpr int MESH_INTERVAL = 15;
// The probe's map size: RoomProbe's default in step mode, and the live benchmark's.
constexpr int STEP_PROBE_SIZE = 128;
constexpr int LIVE_PROBE_SIZE = 256;

// Per-frame values of one stage.
struct Series {
	std::vector<double> values;

	void add(double p_value) { values.push_back(p_value); }
	bool empty() const { return values.empty(); }
	size_t size() const { return values.size(); }
	double percentile(double p_fraction) const {
		if (values.empty()) {
			return 0.0;
		}
		std::vector<double> v = values;
		std::sort(v.begin(), v.end());
		// Nearest rank.
		const size_t rank = size_t(std::ceil(p_fraction * double(v.size())));
		return v[std::min(v.size() - 1, rank > 0 ? rank - 1 : 0)];
	}
	double median() const {
		if (values.empty()) {
			return 0.0;
		}
		std::vector<double> v = values;
		std::sort(v.begin(), v.end());
		const size_t n = v.size();
		return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
	}
	double mean() const {
		double sum = 0.0;
		for (double x : values) {
			sum += x;
		}
		return values.empty() ? 0.0 : sum / double(values.size());
	}
};

// A probe map's published timings (ProbeMap), one value per map.
struct MapSeries {
	Series coarse, dense, sh, mips, total;

	void add(const ProbeMap &p_map);
};

// A probe map's rows against Table 1: p_names are the five rows' names, the first a format taking
// the face size, the second the face size and the dense pass's scale.
void print_map_rows(const MapSeries &p_map, const std::array<const char *, 5> &p_names, int p_probe_size, int p_dense_scale);

// Paper value < 0: the paper has no such row.
void print_row(const char *p_name, const Series &p_series, double p_paper_ms = -1.0, const char *p_paper_name = "");
void print_table_header(const char *p_title);
const char *met(bool p_met);
// A figure for the summary line: "nan" when there is none.
std::string figure(bool p_has, double p_value);

// What dense SLAM did over a sequence.
struct SlamFigures {
	Series undistort, track, integrate, raycast, process, track_integrate, mesh;
	Series mesh_copy, mesh_build; // the engine's re-mesh: the copy (SLAM thread), the meshing (mesh worker)
	int good = 0, poor = 0, lost = 0;
	size_t mesh_triangles = 0;
	Trajectory reported; // every frame's reported pose (the held one when Lost), for ATE and RPE
};

void record_timings(const DenseSlamTimings &p_timings, bool p_integrated, SlamFigures *r_figures);
void record_state(TrackingState p_state, SlamFigures *r_figures);
void record_pose(double p_t_s, const Pose &p_pose, SlamFigures *r_figures);

// --save-trajectory FILE: the tracked poses in TUM's format as they come, one line per frame
// tracked Good or Poor; a Poor frame's line follows a comment with its reason, a Lost frame has
// only a comment (no pose is known there: the tracker holds its last one).
class TrajectoryFile {
public:
	// False after printing the problem.
	bool open(const std::string &p_path, const std::string &p_source, const std::string &p_world);
	void add(double p_t_s, const Pose &p_pose, TrackingState p_state, const std::string &p_reason);
	void close(const std::string &p_path);

private:
	void report(const std::string &p_error);

	TumTrajectoryWriter writer;
	bool failed = false;
};

// One frame as the engine published it: its timings, state and (reported, the held one when
// Lost, as the application would use it) pose.
void record_tracked_frame(const TrackedFrame &p_frame, SlamFigures *r_figures, TrajectoryFile *r_file);

// ATE and RPE of a trajectory against the ground truth (eval/trajectory_metrics.h).
struct Accuracy {
	AbsoluteTrajectoryError ate;
	RelativePoseError per_frame, per_second;
	bool has() const { return ate.count > 0; }
};

// p_targets: print the issue's target (synthetic recordings only).
Accuracy print_accuracy(const Trajectory &p_estimate, const Trajectory &p_truth, const SlamFigures &p_figures, bool p_targets, const char *p_what);
// The accuracy keys of a summary line.
std::string accuracy_summary(const Accuracy &p_accuracy);
// The summary's backend key: "backend=cpu" or "backend=vulkan" where the kernels ran, or
// "backend=cpu_fallback" when p_asked was not the CPU and they ran there (the header says why).
std::string backend_summary(ComputeBackend p_asked, bool p_on_device);
// Where the device path's time went (#40's profile): each kind of batch the process's device ran,
// its count a frame, its time on the calling thread and on the device. Nothing for the CPU backend.
void print_device_batches(ComputeBackend p_backend, size_t p_frames);
void print_memory(const TsdfStats &p_stats);
void print_slam_rows(const SlamFigures &p_figures, const char *p_mesh_name);
void print_slam_target(const SlamFigures &p_figures, int p_width, int p_height);
void print_settings(const DenseSlamOptions &p_slam);
// Every issue the reader met, each once (issue #38: they were counted, and five at most listed).
void print_issues(FILE *p_out, const RecordingReader &p_reader);
void print_threads();

struct Arguments {
	std::string mode; // slam or live
	std::string recording, tum, seven_scenes;
	long frames = -1; // RGB-D frames to process; -1: all
	int threads = 0; // 0: the libraries' defaults
	int probe_size = 0; // 0: the mode's default
	ComputeBackend backend = ComputeBackend::Cpu; // --backend: where the kernels with a GPU twin run
	int probes = 1; // slam --recording: probes rendered every frame (the first at the probe, the others around it)
	double speed = 1.0; // live: playback speed
	long warmup_frames = 0; // soak: frames before memory and time are judged (0: a fifth of them)
	std::string rig_file; // --rig: the RGB-D camera of this rig file
	bool has_intrinsics = false; // --intrinsics fx,fy,cx,cy
	double intrinsics[4] = { 0.0, 0.0, 0.0, 0.0 };
	std::string save_trajectory; // --save-trajectory FILE
	bool force = false; // --force: --save-trajectory may replace an existing file
	bool peers = true; // slam --recording: OpenCV's TSDF and ICP on the same frames (--no-peers: not)
	std::string open3d_results; // --open3d-results FILE: Open3D's medians on the same frames (open3d_peer.py --out)
	DenseSlamOptions slam; // the defaults, with --voxel-size-m, --colour-weight and the ranges applied
};

// The command line (bench_args.cpp).
void print_usage(std::FILE *p_out);
int usage(const char *p_error); // prints the usage; the exit status 2
// The options after the benchmark's name into *r_args (mode set): -1 to run it, else the exit status.
int parse_arguments(int p_argc, char **p_argv, Arguments *r_args);
int run_decode(int p_argc, char **p_argv);

// The benchmarks.
int bench_recording(const Arguments &p_args); // slam --recording
int bench_live(const Arguments &p_args);
int bench_soak(const Arguments &p_args);
int bench_tum(const Arguments &p_args);
int bench_7scenes(const Arguments &p_args);

} // namespace roomprobe::bench
