#include <slam/icp_accumulate_simd.h>
#include "bench_common.h"

#include <gpu/compute_device.h>

#include <io/opencv.h>

#include <tbb/global_control.h>

namespace roomprobe::bench {

namespace {

// The issue's targets.
constexpr double TARGET_SLAM_MS = 33.0; // tracking + integration, median, 640x480
constexpr double TARGET_ATE_MM = 10.0; // ATE RMSE on the synthetic sequences

} // namespace

void MapSeries::add(const ProbeMap &p_map) {
	coarse.add(p_map.coarse_ms);
	dense.add(p_map.dense_ms);
	sh.add(p_map.sh_ms);
	mips.add(p_map.mips_ms);
	total.add(p_map.total_ms);
}

void print_row(const char *p_name, const Series &p_series, double p_paper_ms, const char *p_paper_name) {
	if (p_series.empty()) {
		std::printf("  %-40s %5d %9s %9s %9s", p_name, 0, "-", "-", "-");
	} else {
		std::printf("  %-40s %5zu %9.2f %9.2f %9.2f", p_name, p_series.values.size(), p_series.median(), p_series.mean(), p_series.percentile(0.9));
	}
	if (p_paper_ms >= 0.0) {
		std::printf("   %6.2f  %s", p_paper_ms, p_paper_name);
	}
	std::printf("\n");
}

void print_map_rows(const MapSeries &p_map, const std::array<const char *, 5> &p_names, int p_probe_size, int p_dense_scale) {
	char name[96];
	std::snprintf(name, sizeof(name), p_names[0], p_probe_size);
	print_row(name, p_map.coarse, 0.91, "Render cubemap (coarse), 256^2");
	std::snprintf(name, sizeof(name), p_names[1], p_probe_size, p_dense_scale);
	print_row(name, p_map.dense, 7.46, "Render cubemap (dense), 256^2");
	print_row(p_names[2], p_map.sh);
	print_row(p_names[3], p_map.mips);
	print_row(p_names[4], p_map.total);
}

void print_table_header(const char *p_title) {
	std::printf("%s\n", p_title);
	std::printf("  %-40s %5s %9s %9s %9s   %s\n", "stage (ms)", "n", "median", "mean", "p90", "paper Table 1");
}

const char *met(bool p_met) {
	return p_met ? "MET" : "NOT MET";
}

std::string figure(bool p_has, double p_value) {
	if (!p_has) {
		return "nan";
	}
	char text[32];
	std::snprintf(text, sizeof(text), "%.2f", p_value);
	return text;
}

void record_timings(const DenseSlamTimings &p_timings, bool p_integrated, SlamFigures *r_figures) {
	r_figures->undistort.add(p_timings.undistort_ms);
	r_figures->track.add(p_timings.track_ms);
	if (p_integrated) {
		r_figures->integrate.add(p_timings.integrate_ms);
		r_figures->raycast.add(p_timings.raycast_ms);
	}
	r_figures->track_integrate.add(p_timings.track_ms + p_timings.integrate_ms);
	r_figures->process.add(p_timings.frame_ms);
}

void record_state(TrackingState p_state, SlamFigures *r_figures) {
	switch (p_state) {
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
}

void record_pose(double p_t_s, const Pose &p_pose, SlamFigures *r_figures) {
	std::string error;
	if (!r_figures->reported.append(TimedPose{ p_t_s, p_pose }, &error)) {
		std::fprintf(stderr, "roomprobe_bench: pose at %.6f s left out of the accuracy: %s\n", p_t_s, error.c_str());
	}
}

// ---------------------------------------------------------------- TrajectoryFile

bool TrajectoryFile::open(const std::string &p_path, const std::string &p_source, const std::string &p_world) {
	if (p_path.empty()) {
		return true;
	}
	const std::string error = writer.open(p_path,
			{ "RoomProbe roomprobe_bench " + p_source + ": the tracked RGB-D camera, world_from_camera, seconds and metres",
					"one pose line per frame tracked good or poor; a poor frame's line follows '# <t> poor: <reason>';",
					"a lost frame has only the comment '# <t> lost: <reason>' (the tracker held its last pose there)", "world frame: " + p_world });
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --save-trajectory: %s\n", error.c_str());
		return false;
	}
	return true;
}

void TrajectoryFile::add(double p_t_s, const Pose &p_pose, TrackingState p_state, const std::string &p_reason) {
	if (!writer.is_open() || failed) {
		return;
	}
	char time[32];
	std::snprintf(time, sizeof(time), "%.6f", p_t_s);
	std::string error;
	if (p_state != TrackingState::Good) {
		error = writer.add_comment(std::string(time) + " " + tracking_state_name(p_state) + ": " + (p_reason.empty() ? "-" : p_reason));
	}
	if (error.empty() && p_state != TrackingState::Lost) {
		error = writer.add_pose(TimedPose{ p_t_s, p_pose });
	}
	report(error);
}

void TrajectoryFile::close(const std::string &p_path) {
	if (!writer.is_open()) {
		return;
	}
	report(writer.close());
	if (!failed) {
		std::printf("  trajectory saved: %s (TUM format; lost frames as comments)\n", p_path.c_str());
	}
}

void TrajectoryFile::report(const std::string &p_error) {
	if (!p_error.empty() && !failed) {
		std::fprintf(stderr, "roomprobe_bench: --save-trajectory: %s\n", p_error.c_str());
		failed = true;
	}
}

void record_tracked_frame(const TrackedFrame &p_frame, SlamFigures *r_figures, TrajectoryFile *r_file) {
	record_timings(p_frame.timings, p_frame.integrated, r_figures);
	record_state(p_frame.state, r_figures);
	if (p_frame.has_pose) {
		record_pose(p_frame.timestamp_s, p_frame.world_from_camera, r_figures);
		r_file->add(p_frame.timestamp_s, p_frame.world_from_camera, p_frame.state, p_frame.reason);
	}
}

// ---------------------------------------------------------------- accuracy, memory, SLAM rows

Accuracy print_accuracy(const Trajectory &p_estimate, const Trajectory &p_truth, const SlamFigures &p_figures, bool p_targets, const char *p_what) {
	Accuracy accuracy;
	accuracy.ate = absolute_trajectory_error(p_estimate, p_truth);
	accuracy.per_frame = relative_pose_error(p_estimate, p_truth, 1.0, RpeDelta::Frames);
	accuracy.per_second = relative_pose_error(p_estimate, p_truth, 1.0, RpeDelta::Seconds);
	std::printf("accuracy of %s (against the ground truth at the same timestamps, same world frame, no alignment):\n", p_what);
	std::printf("  tracking states: %d good, %d poor, %d lost\n", p_figures.good, p_figures.poor, p_figures.lost);
	if (!accuracy.has()) {
		std::printf("  no ground-truth poses at the frames' timestamps: no ATE or RPE\n");
		return accuracy;
	}
	const AbsoluteTrajectoryError &ate = accuracy.ate;
	std::printf("  frames compared: %zu (ground-truth path %.0f mm)\n", ate.count, 1000.0 * ate.path_m);
	std::printf("  ATE RMSE (translation): %.2f mm   max %.2f mm (t = %.3f s)   rotation RMSE %.3f deg\n", 1000.0 * ate.rmse_m, 1000.0 * ate.max_m,
			ate.max_at_s, ate.rotation_rmse_deg);
	for (const auto &[rpe, unit] : { std::pair{ &accuracy.per_frame, "frame" }, std::pair{ &accuracy.per_second, "s" } }) {
		if (rpe->pairs == 0) {
			std::printf("  RPE per %s: no pairs\n", unit);
			continue;
		}
		std::printf("  RPE per %-5s (%4zu pairs): translation RMSE %.2f mm (mean %.2f, max %.2f)   rotation RMSE %.3f deg (mean %.3f, max %.3f)\n",
				unit, rpe->pairs, 1000.0 * rpe->translation_rmse_m, 1000.0 * rpe->translation_mean_m, 1000.0 * rpe->translation_max_m,
				rpe->rotation_rmse_deg, rpe->rotation_mean_deg, rpe->rotation_max_deg);
	}
	if (p_targets) {
		std::printf("  TARGET ATE RMSE <= %.0f mm on the synthetic sequences: %s\n", TARGET_ATE_MM, met(1000.0 * ate.rmse_m <= TARGET_ATE_MM));
	}
	return accuracy;
}

std::string accuracy_summary(const Accuracy &p_accuracy) {
	const bool rpe = p_accuracy.per_frame.pairs > 0;
	return "ate_mm=" + figure(p_accuracy.has(), 1000.0 * p_accuracy.ate.rmse_m) + " ate_max_mm=" + figure(p_accuracy.has(), 1000.0 * p_accuracy.ate.max_m) +
			" rpe_mm_per_frame=" + figure(rpe, 1000.0 * p_accuracy.per_frame.translation_rmse_m) +
			" rpe_deg_per_frame=" + figure(rpe, p_accuracy.per_frame.rotation_rmse_deg);
}

std::string backend_summary(ComputeBackend p_asked, bool p_on_device) {
	return p_on_device ? "backend=vulkan" : p_asked == ComputeBackend::Cpu ? "backend=cpu" : "backend=cpu_fallback";
}

void print_device_batches(ComputeBackend p_backend, size_t p_frames) {
	std::string reason;
	const std::shared_ptr<ComputeDevice> device = p_backend == ComputeBackend::Cpu ? nullptr : shared_compute_device(p_backend, &reason);
	if (!device || p_frames == 0) {
		return;
	}
	std::vector<GpuBatchStats> kinds = device->batch_stats();
	std::sort(kinds.begin(), kinds.end(), [](const GpuBatchStats &p_a, const GpuBatchStats &p_b) { return p_a.wall_ms > p_b.wall_ms; });
	std::printf("device batches on %s (wall: the calling thread, recording to the fence's end; device: the GPU's timestamps); buffers: "
				"%.1f MiB in device memory, %.1f MiB in host memory\n",
			device->name().c_str(), double(device->device_memory_bytes()) / 1048576.0, double(device->host_memory_bytes()) / 1048576.0);
	std::printf("  %-44s %9s %12s %14s %12s\n", "kernels", "a frame", "wall ms a fr", "device ms a fr", "host share");
	const double frames = double(p_frames);
	double wall = 0.0, on_device = 0.0;
	for (const GpuBatchStats &k : kinds) {
		char device_ms[32] = "-", host_share[32] = "-";
		if (k.timed) {
			std::snprintf(device_ms, sizeof(device_ms), "%.3f", k.device_ms / frames);
			std::snprintf(host_share, sizeof(host_share), "%.0f%%", k.wall_ms > 0.0 ? 100.0 * (1.0 - k.device_ms / k.wall_ms) : 0.0);
		}
		std::printf("  %-44s %9.2f %12.3f %14s %12s\n", k.kind.c_str(), double(k.batches) / frames, k.wall_ms / frames, device_ms, host_share);
		wall += k.wall_ms;
		on_device += k.device_ms;
	}
	std::printf("  %-44s %9s %12.3f %14.3f\n", "all", "", wall / frames, on_device / frames);
}

void print_memory(const TsdfStats &p_stats) {
	const TsdfStats &s = p_stats;
	std::printf("memory (TSDF at the end):\n");
	std::printf("  allocated blocks %d of %d   bytes used %.1f MiB (%zu)   reserved %.1f MiB   evicted %lld   dropped %lld\n", s.allocated_blocks,
			s.capacity_blocks, double(s.bytes_used) / (1024.0 * 1024.0), s.bytes_used, double(s.bytes_reserved) / (1024.0 * 1024.0),
			s.evicted_blocks_total, s.dropped_blocks_total);
	std::printf("  bounds [%.2f %.2f %.2f] .. [%.2f %.2f %.2f] m\n", s.bounds_min.x, s.bounds_min.y, s.bounds_min.z, s.bounds_max.x, s.bounds_max.y,
			s.bounds_max.z);
}

void print_slam_rows(const SlamFigures &p_figures, const char *p_mesh_name) {
	print_row("undistort (RGB-D)", p_figures.undistort);
	print_row("tracking", p_figures.track);
	print_row("integration (fused frames)", p_figures.integrate);
	print_row("raycast (fused frames)", p_figures.raycast);
	print_row("SLAM process (whole call)", p_figures.process, 3.16, "SLAM Update (GPU)");
	if (!p_figures.mesh.empty()) {
		print_row(p_mesh_name, p_figures.mesh);
	}
}

void print_slam_target(const SlamFigures &p_figures, int p_width, int p_height) {
	const double median = p_figures.track_integrate.median();
	std::printf("  TARGET tracking + integration median <= %.0f ms per frame at 640x480: %.2f ms (per-frame sum, %dx%d): %s\n", TARGET_SLAM_MS, median,
			p_width, p_height, met(median <= TARGET_SLAM_MS && p_width == 640 && p_height == 480));
}

void print_settings(const DenseSlamOptions &p_slam) {
	const TsdfOptions &tsdf = p_slam.tsdf;
	const IcpOptions &icp = p_slam.icp;
	std::printf("  SLAM settings: voxel %.1f mm, truncation %.0f mm, TSDF depth %.2f..%.2f m; ICP depth %.2f..%.2f m, colour weight %.3f, "
				"colour %s, colour slide %.3f m / %.2f deg, max jump %.3f m / %.1f deg, max speed %.1f m/s, noise reference %.2f m, %d levels, finest stride %d, point-to-plane rows %s; raycast level %d (normals from %s), tracking level %d, fuse poor frames %s, young model %d frames x %.2f\n",
			1000.0 * tsdf.voxel_size_m, 1000.0 * tsdf.truncation_m, double(tsdf.min_depth_m), double(tsdf.max_depth_m), icp.min_depth_m, icp.max_depth_m,
			icp.colour_weight, icp.colour_always ? "at every level" : "where the geometry is weak", icp.max_colour_slide_m, icp.max_colour_slide_deg, icp.max_jump_m, icp.max_jump_deg, p_slam.max_speed_m_s, icp.depth_noise.b_per_m2 > 0.0 ? icp.depth_noise.reference_m : 0.0, icp.levels, icp.finest_stride_px,
			icp.simd && icp_simd_available() ? "AVX2" : "scalar", p_slam.raycast_level, p_slam.reference_normals_from_points ? "points" : "the gradient", p_slam.tracking_level, p_slam.integrate_poor ? "yes" : "no",
			p_slam.young_model_frames, p_slam.young_model_noise_factor);
}

void print_issues(FILE *p_out, const RecordingReader &p_reader) {
	for (const std::string &line : issue_lines(p_reader.get_issues())) {
		std::fprintf(p_out, "  issue: %s\n", line.c_str());
	}
}

void print_threads() {
	std::printf("  threads: OpenCV %d, TBB %zu\n", cv::getNumThreads(), tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

} // namespace roomprobe::bench
