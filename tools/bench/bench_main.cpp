// roomprobe_bench: where the time of a live frame goes, and how accurate tracking is.
//
// slam --recording DIR: replays a RoomProbe recording through the whole live pipeline, every
// event in time order, as the Godot nodes run it (DenseSLAM, CoarseRoomModel, RoomProbe):
//   RGB-D frame:   DenseSlam::process (from room.yaml's initial_rgb_pose); every 15 fused frames
//                  DenseSlam::update_mesh; then probe 0's environment map: the coarse model's
//                  cubemap (128^2) and the dense model painted over it (render_dense_over);
//   fisheye frame: its pose from the TRACKED trajectory (fisheye_pose_at, 0.1 s extrapolation,
//                  as the node), then CoarsePipeline::add_fisheye_frame (async inpainting, gain
//                  lighting compensation).
// Prints per-stage median, mean and p90 against the paper's Table 1, the full frame time, the
// dense cubemap's cost at three raycast scales and two sizes, ATE against the ground truth, and
// the TSDF's memory. Reading and decoding the images is not timed.
//
// slam --tum DIR: dense SLAM alone on a TUM RGB-D sequence, from the ground-truth pose of the
// first frame that has one; the same timings and ATE.
//
// Prints figures; asserts nothing (the targets are reported as met or not).
//
// usage: roomprobe_bench slam (--recording DIR | --tum DIR) [--frames N] [--threads N]

#include "../common/cli.h"

#include <camera/pinhole_camera.h>
#include <envmap/cubemap.h>
#include <envmap/dense_render.h>
#include <pipeline/coarse_pipeline.h>
#include <recording/recording_reader.h>
#include <recording/tum_dataset.h>
#include <rig/fisheye_pose.h>
#include <rig/trajectory.h>
#include <slam/dense_slam.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

// The issue's targets.
constexpr double TARGET_SLAM_MS = 33.0; // tracking + integration, median, 640x480
constexpr double TARGET_ATE_MM = 10.0; // ATE RMSE on the synthetic sequences
constexpr double PAPER_FRAME_MS = 47.42; // Table 1's total
// As the live nodes: DenseSLAM's mesh_update_interval and fisheye extrapolation, RoomProbe's map size.
constexpr int MESH_INTERVAL = 15;
constexpr double FISHEYE_EXTRAPOLATION_S = 0.1;
constexpr int LIVE_CUBEMAP_SIZE = 128;
// Repeats of each dense cubemap option on the final model (median taken).
constexpr int OPTION_REPEATS = 5;

// Per-frame values of one stage.
struct Series {
	std::vector<double> values;

	void add(double p_value) { values.push_back(p_value); }
	bool empty() const { return values.empty(); }
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

// Paper value < 0: the paper has no such row.
void print_row(const char *p_name, const Series &p_series, double p_paper_ms = -1.0, const char *p_paper_name = "") {
	if (p_series.empty()) {
		std::printf("  %-36s %5d %9s %9s %9s", p_name, 0, "-", "-", "-");
	} else {
		std::printf("  %-36s %5zu %9.2f %9.2f %9.2f", p_name, p_series.values.size(), p_series.median(), p_series.mean(), p_series.percentile(0.9));
	}
	if (p_paper_ms >= 0.0) {
		std::printf("   %6.2f  %s", p_paper_ms, p_paper_name);
	}
	std::printf("\n");
}

void print_table_header(const char *p_title) {
	std::printf("%s\n", p_title);
	std::printf("  %-36s %5s %9s %9s %9s   %s\n", "stage (ms)", "n", "median", "mean", "p90", "paper Table 1");
}

const char *met(bool p_met) {
	return p_met ? "MET" : "NOT MET";
}

// What DenseSlam did over a sequence.
struct SlamFigures {
	Series undistort, track, integrate, raycast, process, track_integrate, mesh;
	int good = 0, poor = 0, lost = 0;
	size_t mesh_triangles = 0;
	// Accuracy: frames with a ground-truth pose at their timestamp.
	int compared = 0;
	double sum_squared_m2 = 0.0, max_error_m = 0.0, sum_squared_rot_deg2 = 0.0;
	double max_error_t_s = 0.0;
	double path_m = 0.0; // ground-truth path length over the compared frames
	bool has_last_truth = false;
	glm::dvec3 last_truth = glm::dvec3(0.0);
};

double rotation_error_deg(const glm::dquat &p_a, const glm::dquat &p_b) {
	const double d = std::min(1.0, std::abs(glm::dot(p_a, p_b)));
	return 2.0 * std::acos(d) * 180.0 / M_PI;
}

// Records one processed frame's timings and state, and its error against p_truth when it has one.
void record_slam_frame(const DenseSlamFrame &p_frame, double p_t_s, const Trajectory *p_truth, SlamFigures *r_figures) {
	const DenseSlamTimings &t = p_frame.timings;
	r_figures->undistort.add(t.undistort_ms);
	r_figures->track.add(t.track_ms);
	if (p_frame.integrated) {
		r_figures->integrate.add(t.integrate_ms);
		r_figures->raycast.add(t.raycast_ms);
	}
	r_figures->track_integrate.add(t.track_ms + t.integrate_ms);
	r_figures->process.add(t.frame_ms);
	switch (p_frame.tracking.state) {
		case TrackingState::Good:
			r_figures->good++;
			break;
		case TrackingState::Poor:
			r_figures->poor++;
			break;
		case TrackingState::Lost:
			r_figures->lost++;
			break;
	}
	Pose truth;
	std::string error;
	if (p_truth == nullptr || p_truth->is_empty() || !p_truth->pose_at(p_t_s, &truth, &error)) {
		return;
	}
	// The reported pose (the held one when Lost), as the application would use it.
	const double e = glm::length(p_frame.tracking.world_from_camera.translation - truth.translation);
	const double r = rotation_error_deg(p_frame.tracking.world_from_camera.rotation, truth.rotation);
	r_figures->compared++;
	r_figures->sum_squared_m2 += e * e;
	r_figures->sum_squared_rot_deg2 += r * r;
	if (e > r_figures->max_error_m) {
		r_figures->max_error_m = e;
		r_figures->max_error_t_s = p_t_s;
	}
	if (r_figures->has_last_truth) {
		r_figures->path_m += glm::length(truth.translation - r_figures->last_truth);
	}
	r_figures->last_truth = truth.translation;
	r_figures->has_last_truth = true;
}

void print_accuracy(const SlamFigures &p_figures, bool p_synthetic) {
	std::printf("accuracy (tracked RGB-D poses against the ground truth at the same timestamps, same world frame, no alignment):\n");
	std::printf("  tracking states: %d good, %d poor, %d lost\n", p_figures.good, p_figures.poor, p_figures.lost);
	if (p_figures.compared == 0) {
		std::printf("  no ground-truth poses at the frames' timestamps: no ATE\n");
		return;
	}
	const double rmse_mm = 1000.0 * std::sqrt(p_figures.sum_squared_m2 / double(p_figures.compared));
	std::printf("  frames compared: %d (ground-truth path %.0f mm)\n", p_figures.compared, 1000.0 * p_figures.path_m);
	std::printf("  ATE RMSE (translation): %.2f mm   max %.2f mm (t = %.3f s)   rotation RMSE %.3f deg\n", rmse_mm, 1000.0 * p_figures.max_error_m,
			p_figures.max_error_t_s, std::sqrt(p_figures.sum_squared_rot_deg2 / double(p_figures.compared)));
	if (p_synthetic) {
		std::printf("  TARGET ATE RMSE <= %.0f mm on the synthetic sequences: %s\n", TARGET_ATE_MM, met(rmse_mm <= TARGET_ATE_MM));
	}
}

void print_memory(const DenseSlam &p_slam) {
	const TsdfStats s = p_slam.volume().stats();
	std::printf("memory (TSDF at the end):\n");
	std::printf("  allocated blocks %d of %d   bytes used %.1f MiB (%zu)   reserved %.1f MiB   evicted %lld   dropped %lld\n", s.allocated_blocks,
			s.capacity_blocks, double(s.bytes_used) / (1024.0 * 1024.0), s.bytes_used, double(s.bytes_reserved) / (1024.0 * 1024.0),
			s.evicted_blocks_total, s.dropped_blocks_total);
	std::printf("  bounds [%.2f %.2f %.2f] .. [%.2f %.2f %.2f] m\n", s.bounds_min.x, s.bounds_min.y, s.bounds_min.z, s.bounds_max.x, s.bounds_max.y,
			s.bounds_max.z);
}

void print_slam_rows(const SlamFigures &p_figures) {
	print_row("undistort (RGB-D)", p_figures.undistort);
	print_row("tracking", p_figures.track);
	print_row("integration (fused frames)", p_figures.integrate);
	print_row("raycast (fused frames)", p_figures.raycast);
	print_row("SLAM process (whole call)", p_figures.process, 3.16, "SLAM Update (GPU)");
	if (!p_figures.mesh.empty()) {
		char name[64];
		std::snprintf(name, sizeof(name), "meshing (per call, every %d fused)", MESH_INTERVAL);
		print_row(name, p_figures.mesh);
	}
}

void print_slam_target(const SlamFigures &p_figures, int p_width, int p_height) {
	const double median = p_figures.track_integrate.median();
	std::printf("  TARGET tracking + integration median <= %.0f ms per frame at 640x480: %.2f ms (per-frame sum, %dx%d): %s\n", TARGET_SLAM_MS, median,
			p_width, p_height, met(median <= TARGET_SLAM_MS && p_width == 640 && p_height == 480));
}

struct Arguments {
	std::string recording, tum;
	long frames = -1; // RGB-D frames to process; -1: all
	int threads = 0; // 0: the libraries' defaults
};

int usage(const char *p_error) {
	if (p_error != nullptr) {
		std::fprintf(stderr, "roomprobe_bench: %s\n", p_error);
	}
	std::fprintf(stderr,
			"usage: roomprobe_bench slam (--recording DIR | --tum DIR) [--frames N] [--threads N]\n"
			"  --recording DIR  a RoomProbe recording: the full live pipeline (SLAM, coarse model, probe 0's map)\n"
			"  --tum DIR        a TUM RGB-D sequence (rgb.txt, depth.txt, groundtruth.txt): dense SLAM only\n"
			"  --frames N       stop after N RGB-D frames (default: all)\n"
			"  --threads N      worker threads for OpenCV and TBB (default: the libraries')\n");
	return 2;
}

// ---------------------------------------------------------------- recording

// The probe's map is rendered at probe 0, or the floorplan's centre at 0.9 m when room.yaml has none.
glm::dvec3 probe_position(const RoomInfo &p_room, bool *r_from_file) {
	*r_from_file = !p_room.probes.empty();
	if (*r_from_file) {
		return p_room.probes[0];
	}
	glm::dvec3 centre(0.0, 0.9, 0.0);
	for (const Vec2 &p : p_room.floorplan.points) {
		centre.x += p.x / double(p_room.floorplan.points.size());
		centre.z += p.y / double(p_room.floorplan.points.size());
	}
	return centre;
}

int bench_recording(const Arguments &p_args) {
	RecordingReader reader;
	const RecordingStatus status = reader.open(p_args.recording);
	if (!status.ok) {
		std::fprintf(stderr, "roomprobe_bench: --recording: %s\n", status.error.c_str());
		return 1;
	}
	if (!reader.has_room()) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no room.yaml room\n", p_args.recording.c_str());
		return 1;
	}
	if (reader.rgbd_count() == 0) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no usable RGB-D frames\n", p_args.recording.c_str());
		return 1;
	}
	const Rig &rig = reader.get_rig();
	const RoomInfo &room = reader.get_room();

	DenseSlam slam;
	std::string error = slam.configure(rig.rgb, room.initial_rgb_pose);
	if (error.empty()) {
		// As the DenseSLAM node: eviction spares the probes' surroundings longest.
		slam.volume().set_keep_points(room.probes);
	}
	CoarsePipelineOptions coarse_options;
	coarse_options.inpaint_async = true; // as CoarseRoomModel: off the frame's critical path
	coarse_options.lighting = true;
	coarse_options.lighting_model = LightingModel::GAIN_ROBUST;
	coarse_options.cubemap_size = LIVE_CUBEMAP_SIZE;
	CoarsePipeline coarse(coarse_options);
	if (error.empty()) {
		error = coarse.configure(rig, room.floorplan);
	}
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: %s\n", p_args.recording.c_str(), error.c_str());
		return 1;
	}
	bool probe_from_file = false;
	const glm::dvec3 probe = probe_position(room, &probe_from_file);
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	const size_t rgbd_total = p_args.frames > 0 ? std::min(reader.rgbd_count(), size_t(p_args.frames)) : reader.rgbd_count();

	std::printf("roomprobe_bench slam --recording %s\n", p_args.recording.c_str());
	std::printf("  RGB-D %dx%d, %zu of %zu frames; fisheye %dx%d, %zu frames in the recording; %zu recording issues\n", rig.rgb.width, rig.rgb.height,
			rgbd_total, reader.rgbd_count(), rig.fisheye.width, rig.fisheye.height, reader.fisheye_count(), reader.get_issues().size());
	std::printf("  probe %s at [%.2f %.2f %.2f]; voxel %.0f mm, truncation %.0f mm; coarse texel %.0f mm, async inpainting, gain lighting\n",
			probe_from_file ? "0" : "(none in room.yaml: floorplan centre)", probe.x, probe.y, probe.z, 1000.0 * slam.options().tsdf.voxel_size_m,
			1000.0 * slam.options().tsdf.truncation_m, 1000.0 * coarse_options.texel_size_m);
	std::printf("  threads: OpenCV %d, TBB %zu\n", cv::getNumThreads(),
			tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

	SlamFigures figures;
	Series occlusion, lighting, update, inpaint, coarse_frame, cubemap_coarse, cubemap_dense, live_frame;
	Series fisheye_error_mm;
	Trajectory tracked; // the trusted poses, for the fisheye's (as the DenseSLAM node keeps them)
	DenseLighting dense_lighting;
	int fused_since_mesh = 0;
	size_t rgbd_done = 0, fisheye_done = 0, fisheye_skipped = 0, frames_failed = 0, occlusion_skipped = 0;
	std::string first_skip;
	for (const PlaybackEvent &event : reader.get_events()) {
		if (event.stream == RecordingStream::Rgbd) {
			if (rgbd_done >= rgbd_total) {
				break;
			}
			const RgbdFrameResult frame = reader.read_rgbd(event.index);
			if (!frame.ok) {
				std::fprintf(stderr, "roomprobe_bench: %s (frame skipped)\n", frame.error.c_str());
				frames_failed++;
				continue;
			}
			rgbd_done++;
			const DenseSlamFrame result = slam.process(frame.frame);
			record_slam_frame(result, frame.frame.timestamp_s, &truth, &figures);
			if (result.tracking.state != TrackingState::Lost) {
				std::string append_error;
				tracked.append({ frame.frame.timestamp_s, slam.pose() }, &append_error);
			}
			if (result.integrated && ++fused_since_mesh >= MESH_INTERVAL) {
				fused_since_mesh = 0;
				const Clock::time_point start = Clock::now();
				figures.mesh_triangles = slam.update_mesh().indices.size() / 3;
				figures.mesh.add(ms_since(start));
			}
			// The probe's environment map, as RoomProbe renders it each frame.
			Clock::time_point start = Clock::now();
			Cubemap map = coarse.render_cubemap(probe, true, LIVE_CUBEMAP_SIZE);
			const double coarse_ms = ms_since(start);
			start = Clock::now();
			dense_lighting.render_over(slam.volume(), slam.integrated_count(), coarse.cumulative_lighting(), probe, DenseRenderOptions(), &map);
			const double dense_ms = ms_since(start);
			cubemap_coarse.add(coarse_ms);
			cubemap_dense.add(dense_ms);
			live_frame.add(result.timings.frame_ms + coarse_ms + dense_ms);
		} else {
			const FisheyeFrameResult frame = reader.read_fisheye(event.index);
			if (!frame.ok) {
				std::fprintf(stderr, "roomprobe_bench: %s (frame skipped)\n", frame.error.c_str());
				frames_failed++;
				continue;
			}
			Pose world_from_fisheye;
			std::string pose_error;
			if (tracked.is_empty() || !fisheye_pose_at(tracked, rig, frame.frame.timestamp_s, &world_from_fisheye, &pose_error, FISHEYE_EXTRAPOLATION_S)) {
				// As the node: never integrated at a guess.
				if (first_skip.empty()) {
					first_skip = tracked.is_empty() ? "no tracked pose yet" : pose_error;
				}
				fisheye_skipped++;
				continue;
			}
			Pose true_fisheye;
			if (!truth.is_empty() && fisheye_pose_at(truth, rig, frame.frame.timestamp_s, &true_fisheye, &pose_error)) {
				fisheye_error_mm.add(1000.0 * glm::length(world_from_fisheye.translation - true_fisheye.translation));
			}
			const CoarseFrameStats stats = coarse.add_fisheye_frame(frame.frame, world_from_fisheye);
			occlusion_skipped += stats.occlusion_skipped ? 1 : 0;
			const CoarsePipelineTimings &t = coarse.last_timings();
			occlusion.add(t.occlusion_ms);
			lighting.add(t.lighting_ms);
			update.add(t.update_ms);
			inpaint.add(t.inpaint_ms);
			coarse_frame.add(t.frame_ms);
			fisheye_done++;
		}
	}
	if (rgbd_done == 0) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no RGB-D frame could be read\n", p_args.recording.c_str());
		return 1;
	}
	const Clock::time_point finish_start = Clock::now();
	coarse.finish_inpainting();
	const double finish_ms = ms_since(finish_start);
	const Clock::time_point last_mesh_start = Clock::now();
	figures.mesh_triangles = slam.update_mesh().indices.size() / 3;
	const double last_mesh_ms = ms_since(last_mesh_start);

	std::printf("  processed: %zu RGB-D frames, %zu fisheye frames (%zu skipped without a tracked pose%s%s), %zu unreadable\n\n", rgbd_done, fisheye_done,
			fisheye_skipped, first_skip.empty() ? "" : ", first: ", first_skip.c_str(), frames_failed);

	print_table_header("per-stage timings, ms (n = frames or calls; paper: Table 1, a GPU system, for reference)");
	print_slam_rows(figures);
	std::printf("  coarse model, per fisheye frame:\n");
	print_row("  undistort fisheye (not needed)", Series(), 8.55, "Undistort fisheye image");
	print_row(occlusion_skipped == fisheye_done && fisheye_done > 0 ? "  occlusion (skipped: convex room)" : "  occlusion", occlusion, 0.61,
			"Render occlusion mask");
	print_row("  lighting (gain)", lighting, 21.37, "Estimate brightness");
	print_row("  texture update", update, 0.29, "Update coarse model");
	print_row("  inpaint compose (async request)", inpaint);
	print_row("  coarse frame (whole call)", coarse_frame);
	std::printf("  probe 0's environment map, per RGB-D frame:\n");
	char name[64];
	std::snprintf(name, sizeof(name), "  coarse cubemap render %d^2", LIVE_CUBEMAP_SIZE);
	print_row(name, cubemap_coarse, 0.91, "Render cubemap (coarse), 256^2");
	std::snprintf(name, sizeof(name), "  dense cubemap pass %d^2 (scale %d)", LIVE_CUBEMAP_SIZE, DenseRenderOptions().scale);
	print_row(name, cubemap_dense, 7.46, "Render cubemap (dense), 256^2");
	std::printf("  after the last frame: finish_inpainting %.2f ms, final update_mesh %.2f ms (%zu triangles)\n", finish_ms, last_mesh_ms,
			figures.mesh_triangles);

	// Full frame: the per-RGB-D-frame work, plus the coarse work spread over the RGB-D frames.
	const double fisheye_per_rgbd = double(fisheye_done) / double(rgbd_done);
	const double full_median = live_frame.median() + fisheye_per_rgbd * coarse_frame.median();
	const double full_mean = live_frame.mean() + fisheye_per_rgbd * coarse_frame.mean();
	const double mesh_per_frame = figures.mesh.empty() ? 0.0 : figures.mesh.mean() * double(figures.mesh.values.size()) / double(rgbd_done);
	std::printf("\nfull frame = SLAM process + coarse cubemap + dense cubemap (per RGB-D frame) + %.3f fisheye frames per RGB-D frame x coarse frame:\n",
			fisheye_per_rgbd);
	std::printf("  median-based %.2f ms (%.2f + %.3f x %.2f)   mean-based %.2f ms   paper %.2f ms (GPU system, incl. rendering the scene)\n", full_median,
			live_frame.median(), fisheye_per_rgbd, coarse_frame.median(), full_mean, PAPER_FRAME_MS);
	std::printf("  (meshing, not included: %.2f ms per RGB-D frame amortised)\n", mesh_per_frame);
	print_slam_target(figures, rig.rgb.width, rig.rgb.height);

	// The dense cubemap's cost options on the final model.
	std::printf("\ndense cubemap options on the final model at probe %s (render_dense_over over a coarse render, median of %d):\n",
			probe_from_file ? "0" : "(floorplan centre)", OPTION_REPEATS);
	std::printf("  %-6s %-6s %10s %16s %10s\n", "size", "scale", "ms", "covered texels", "of all");
	const LightingChange change = dense_lighting.update(slam.integrated_count(), coarse.cumulative_lighting());
	for (int size : { 128, 256 }) {
		const Cubemap base = coarse.render_cubemap(probe, true, size);
		for (int scale : { 1, 2, 4 }) {
			DenseRenderOptions options;
			options.scale = scale;
			options.gain = change.gain;
			options.offset = change.offset;
			Series ms;
			int covered = 0;
			for (int repeat = 0; repeat < OPTION_REPEATS; repeat++) {
				Cubemap map = clone_cubemap(base);
				const Clock::time_point start = Clock::now();
				const DenseRenderStats stats = render_dense_over(slam.volume(), probe, options, &map);
				ms.add(ms_since(start));
				covered = stats.texels_covered;
			}
			std::printf("  %3d^2  1/%-4d %10.2f %16d %9.1f%%\n", size, scale, ms.median(), covered, 100.0 * double(covered) / (6.0 * size * size));
		}
	}

	std::printf("\n");
	print_accuracy(figures, true);
	if (!fisheye_error_mm.empty()) {
		std::printf("  fisheye poses from the tracked trajectory: position error median %.2f mm, max %.2f mm (against the ground truth's)\n",
				fisheye_error_mm.median(), fisheye_error_mm.percentile(1.0));
	}
	std::printf("\n");
	print_memory(slam);
	std::printf("  dense mesh: %zu triangles\n", figures.mesh_triangles);
	return 0;
}

// ---------------------------------------------------------------- TUM

int bench_tum(const Arguments &p_args) {
	TumDatasetOptions options;
	TumCamera camera = TumCamera::RosDefault;
	const bool named = tum_camera_from_folder_name(p_args.tum, &camera);
	options.rgb = tum_camera_intrinsics(camera);
	RecordingReader reader;
	const RecordingStatus status = open_tum_dataset(p_args.tum, &reader, options);
	if (!status.ok) {
		std::fprintf(stderr, "roomprobe_bench: --tum: %s\n", status.error.c_str());
		return 1;
	}
	if (reader.rgbd_count() == 0) {
		std::fprintf(stderr, "roomprobe_bench: --tum %s: no usable RGB-D frames (rgb.txt and depth.txt pair none)\n", p_args.tum.c_str());
		return 1;
	}
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	// Start at the first frame the ground truth covers, at its pose: then both share the world frame.
	size_t first = 0;
	Pose initial;
	bool has_initial = false;
	for (; first < reader.rgbd_count() && !truth.is_empty(); first++) {
		std::string error;
		if (truth.pose_at(reader.get_rgbd_ref(first).rgb.timestamp_s, &initial, &error)) {
			has_initial = true;
			break;
		}
	}
	if (!has_initial) {
		first = 0; // no ground truth: the identity, timings only
	}
	DenseSlam slam;
	const std::string error = slam.configure(reader.get_rig().rgb, initial);
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --tum %s: %s\n", p_args.tum.c_str(), error.c_str());
		return 1;
	}
	const size_t available = reader.rgbd_count() - first;
	const size_t total = p_args.frames > 0 ? std::min(available, size_t(p_args.frames)) : available;
	const PinholeParams &rgb = reader.get_rig().rgb;
	std::printf("roomprobe_bench slam --tum %s\n", p_args.tum.c_str());
	std::printf("  %zu RGB-D pairs (%zu processed, from frame %zu), %zu issues; intrinsics %s: fx %.3f fy %.3f cx %.3f cy %.3f%s\n", reader.rgbd_count(),
			total, first, reader.get_issues().size(),
			!named ? "ROS default (folder name gives no freiburg1/2/3)" : camera == TumCamera::Freiburg1 ? "Freiburg1" : camera == TumCamera::Freiburg2 ? "Freiburg2" : "Freiburg3",
			rgb.fx, rgb.fy, rgb.cx, rgb.cy, has_pinhole_distortion(rgb) ? " (with distortion)" : "");
	for (size_t i = 0; i < reader.get_issues().size() && i < 5; i++) {
		std::printf("  issue: %s\n", to_string(reader.get_issues()[i]).c_str());
	}
	if (!has_initial) {
		std::printf("  no ground-truth pose at any frame: starting at the identity, no ATE\n");
	} else {
		std::printf("  start: ground-truth pose at t = %.4f s\n", reader.get_rgbd_ref(first).rgb.timestamp_s);
	}
	std::printf("  threads: OpenCV %d, TBB %zu\n", cv::getNumThreads(),
			tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

	SlamFigures figures;
	size_t done = 0, failed = 0;
	for (size_t i = first; i < first + total; i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		if (!frame.ok) {
			std::fprintf(stderr, "roomprobe_bench: %s (frame skipped)\n", frame.error.c_str());
			failed++;
			continue;
		}
		const DenseSlamFrame result = slam.process(frame.frame);
		record_slam_frame(result, frame.frame.timestamp_s, has_initial ? &truth : nullptr, &figures);
		done++;
	}
	if (done == 0) {
		std::fprintf(stderr, "roomprobe_bench: --tum %s: no RGB-D frame could be read\n", p_args.tum.c_str());
		return 1;
	}
	std::printf("  processed %zu frames, %zu unreadable\n\n", done, failed);
	print_table_header("per-stage timings, ms (paper: Table 1, for reference)");
	print_slam_rows(figures);
	print_slam_target(figures, rgb.width, rgb.height);
	std::printf("\n");
	print_accuracy(figures, false);
	std::printf("\n");
	print_memory(slam);
	return 0;
}

} // namespace

int main(int argc, char **argv) {
	if (argc < 2) {
		return usage(nullptr);
	}
	const std::string verb = argv[1];
	if (verb == "--help" || verb == "-h") {
		usage(nullptr);
		return 0;
	}
	if (verb != "slam") {
		return usage(("unknown benchmark '" + verb + "' (only 'slam')").c_str());
	}
	Arguments args;
	cli::Arguments cursor(argc, argv, 2);
	std::string arg;
	while (cursor.next(&arg)) {
		long n = 0;
		if (arg == "--recording") {
			if (!cursor.value(&args.recording)) {
				return usage("--recording needs a folder");
			}
		} else if (arg == "--tum") {
			if (!cursor.value(&args.tum)) {
				return usage("--tum needs a folder");
			}
		} else if (arg == "--frames") {
			if (!cursor.positive_integer(&n)) {
				return usage("--frames needs a positive integer");
			}
			args.frames = n;
		} else if (arg == "--threads") {
			if (!cursor.positive_integer(&n)) {
				return usage("--threads needs a positive integer");
			}
			args.threads = int(n);
		} else if (arg == "--help" || arg == "-h") {
			usage(nullptr);
			return 0;
		} else {
			return usage(("unknown argument " + arg).c_str());
		}
	}
	if (args.recording.empty() && args.tum.empty()) {
		return usage("--recording or --tum is required");
	}
	// OpenCV's parallel_for_ (SLAM kernels) and TBB (coarse model, cubemaps) each have a pool.
	std::unique_ptr<tbb::global_control> tbb_threads;
	if (args.threads > 0) {
		cv::setNumThreads(args.threads);
		tbb_threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(args.threads));
	}
	int rc = 0;
	if (!args.recording.empty()) {
		rc = bench_recording(args);
	}
	if (rc == 0 && !args.tum.empty()) {
		if (!args.recording.empty()) {
			std::printf("\n");
		}
		rc = bench_tum(args);
	}
	return rc;
}
