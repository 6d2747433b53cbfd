// slam --recording: the engine in step mode (no threads) over every event of a RoomProbe
// recording in time order (bench_main.cpp says what is timed and printed).

#include "bench_speed.h"

#include <envmap/cubemap.h>
#include <envmap/dense_render.h>
#include <envmap/ggx_prefilter.h>
#include <rig/fisheye_pose.h>

#include <array>
#include <numbers>

namespace roomprobe::bench {

namespace {

constexpr double PAPER_FRAME_MS = 47.42; // Table 1's total
// Repeats of each dense cubemap option on the final model (median taken).
constexpr int OPTION_REPEATS = 5;
// --probes N: the probes after the first stand on a horizontal ring around it (inside a room of
// a few metres), so that each sees the room from its own point.
constexpr double EXTRA_PROBE_RING_M = 0.6;

glm::dvec3 extra_probe_offset(int p_index, int p_count) {
	const double angle = 2.0 * std::numbers::pi * double(p_index - 1) / double(std::max(1, p_count - 1));
	return EXTRA_PROBE_RING_M * glm::dvec3(std::cos(angle), 0.0, std::sin(angle));
}

// The run: the engine and what it measured frame by frame.
struct StepRun {
	StepRun(const Arguments &p_args, const RecordingSetup &p_setup) :
			args(p_args), setup(p_setup) {}

	const Arguments &args;
	const RecordingSetup &setup;
	LiveRoom engine;
	int probe_id = 0;
	TrajectoryFile trajectory_file;

	SlamFigures figures;
	Series occlusion, lighting, update, inpaint, coarse_frame;
	MapSeries map;
	Series push_rgbd, push_fisheye, render_call, live_frame;
	Series fisheye_error_mm;
	std::vector<PeerFrame> peer_frames; // the fused frames at their tracked poses
	size_t early_tsdf_bytes = 0; // the TSDF's memory a tenth of the way in
	uint64_t coarse_frames_seen = 0, mesh_version_seen = 0;
	size_t rgbd_done = 0, fisheye_pushed = 0, frames_failed = 0, occlusion_skipped = 0, fisheye_integrated = 0;
	double finish_ms = 0.0, last_mesh_ms = 0.0;
};

// The full frame: the engine's per-RGB-D-frame work, plus its fisheye work spread over the RGB-D frames.
struct FullFrame {
	double fisheye_per_rgbd = 0.0, median = 0.0, mean = 0.0;
};

// A SLAM-only recording: dense SLAM alone on its RGB-D frames.
int bench_dense_recording(const Arguments &p_args, const RecordingSetup &p_setup) {
	const RecordingReader &reader = p_setup.reader();
	DenseSource source;
	source.mode = "recording";
	source.option = "--recording " + p_args.recording;
	source.reader = p_setup.player.shared_reader();
	source.camera = p_setup.camera;
	source.camera_note = p_setup.camera_note.empty() ? "rig.yaml" : p_setup.camera_note;
	source.synthetic = p_setup.synthetic;
	source.has_start_pose = reader.has_room();
	source.start_pose = reader.has_room() ? reader.get_room().initial_rgb_pose : Pose();
	source.skipped = p_setup.engine_skip + ": coarse model and probes skipped, dense SLAM alone (DenseSlam)";
	return bench_dense(p_args, source);
}

// The engine configured with its probes, the header printed, --save-trajectory opened; false
// after printing the problem.
bool start_run(StepRun *r_run) {
	const Arguments &args = r_run->args;
	if (!configure_engine(r_run->setup, "--recording " + args.recording, &r_run->engine)) {
		return false;
	}
	const glm::dvec3 probe = r_run->setup.probe;
	r_run->probe_id = r_run->engine.add_probe(probe, r_run->setup.probe_size);
	for (int i = 1; i < args.probes; i++) {
		r_run->engine.add_probe(probe + extra_probe_offset(i, args.probes), r_run->setup.probe_size);
	}
	print_recording_header("slam", args, r_run->setup, r_run->engine);
	if (args.probes > 1) {
		std::printf("  %d probes: the first at the probe, %d on a ring of %.2f m around it (render_probes times all of them)\n", args.probes,
				args.probes - 1, EXTRA_PROBE_RING_M);
	}
	return r_run->trajectory_file.open(args.save_trajectory, "slam --recording " + args.recording, "the room's (room.yaml's initial pose)");
}

void step_rgbd(RgbdFrame &&p_frame, StepRun *r_run) {
	LiveRoom &engine = r_run->engine;
	r_run->rgbd_done++;
	const cv::Mat depth_for_peers = r_run->args.peers ? p_frame.depth_m : cv::Mat(); // shared, never written
	Clock::time_point start = Clock::now();
	engine.push_rgbd(std::move(p_frame));
	const double push_ms = ms_since(start);
	r_run->push_rgbd.add(push_ms);
	const std::shared_ptr<const TrackedFrame> tracked = engine.tracked_frame();
	if (tracked) {
		record_tracked_frame(*tracked, &r_run->figures, &r_run->trajectory_file);
		if (r_run->args.peers && tracked->integrated) {
			r_run->peer_frames.push_back({ depth_for_peers, tracked->world_from_camera });
		}
	}
	// The engine re-meshes inside push_rgbd every MESH_INTERVAL fused frames: its cost is the
	// call's time beyond SLAM's own (meshing and the placement BVH).
	const std::shared_ptr<const DenseMeshSnapshot> mesh = engine.dense_mesh();
	if (mesh && mesh->version != r_run->mesh_version_seen) {
		r_run->mesh_version_seen = mesh->version;
		r_run->figures.mesh.add(push_ms - (tracked ? tracked->timings.frame_ms : 0.0));
		r_run->figures.mesh_copy.add(mesh->copy_ms);
		r_run->figures.mesh_build.add(mesh->mesh_ms);
		r_run->figures.mesh_triangles = mesh->mesh->indices.size() / 3;
	}
	// The probe's environment map, as RoomProbe takes it each frame.
	start = Clock::now();
	engine.render_probes();
	const double render_ms = ms_since(start);
	r_run->render_call.add(render_ms);
	if (const std::shared_ptr<const ProbeMap> map = engine.probe_map(r_run->probe_id)) {
		r_run->map.add(*map);
	}
	r_run->live_frame.add(push_ms + render_ms);
	if (r_run->rgbd_done == std::max<size_t>(1, r_run->setup.rgbd_total() / 10)) {
		r_run->early_tsdf_bytes = engine.stats().tsdf.bytes_used;
	}
}

void step_fisheye(FisheyeFrame &&p_frame, StepRun *r_run) {
	LiveRoom &engine = r_run->engine;
	const Trajectory &truth = r_run->setup.config.ground_truth;
	// The pose the engine is about to take (step mode: nothing moves in between).
	Pose world_from_fisheye, true_fisheye;
	std::string pose_error;
	if (engine.fisheye_pose(p_frame.timestamp_s, &world_from_fisheye, &pose_error) && !truth.is_empty() &&
			fisheye_pose_at(truth, r_run->setup.config.rig, p_frame.timestamp_s, &true_fisheye, &pose_error)) {
		r_run->fisheye_error_mm.add(1000.0 * glm::length(world_from_fisheye.translation - true_fisheye.translation));
	}
	r_run->fisheye_pushed++;
	const Clock::time_point start = Clock::now();
	engine.push_fisheye(std::move(p_frame));
	const double push_ms = ms_since(start);
	const std::shared_ptr<const CoarseSnapshot> snapshot = engine.coarse_snapshot();
	if (!snapshot || snapshot->frames == r_run->coarse_frames_seen) {
		return; // not integrated (no pose yet): its time is not the coarse model's
	}
	r_run->coarse_frames_seen = snapshot->frames;
	r_run->fisheye_integrated++;
	r_run->push_fisheye.add(push_ms);
	r_run->occlusion_skipped += snapshot->last.occlusion_skipped ? 1 : 0;
	const CoarsePipelineTimings &t = snapshot->timings;
	r_run->occlusion.add(t.occlusion_ms);
	r_run->lighting.add(t.lighting_ms);
	r_run->update.add(t.update_ms);
	r_run->inpaint.add(t.inpaint_ms);
	r_run->coarse_frame.add(t.frame_ms);
}

// Every event the player plays (--frames RGB-D frames), then finish() and a last re-mesh.
void play(StepRun *r_run) {
	const RecordingPlayer &player = r_run->setup.player;
	for (size_t e = 0; e < player.events().size(); e++) {
		SourceFrame frame = player.read(e);
		if (!frame.ok) {
			std::fprintf(stderr, "roomprobe_bench: %s (frame skipped)\n", frame.error.c_str());
			r_run->frames_failed++;
		} else if (frame.event.stream == RecordingStream::Rgbd) {
			step_rgbd(std::move(frame.rgbd), r_run);
		} else {
			step_fisheye(std::move(frame.fisheye), r_run);
		}
	}
	if (r_run->rgbd_done == 0) {
		return;
	}
	const Clock::time_point finish_start = Clock::now();
	r_run->engine.finish();
	r_run->finish_ms = ms_since(finish_start);
	const Clock::time_point last_mesh_start = Clock::now();
	r_run->engine.update_dense_mesh();
	r_run->last_mesh_ms = ms_since(last_mesh_start);
	if (const std::shared_ptr<const DenseMeshSnapshot> mesh = r_run->engine.dense_mesh()) {
		r_run->figures.mesh_triangles = mesh->mesh->indices.size() / 3;
	}
}

// The engine builds this filter once per face size, on its first map (envmap/ggx_prefilter.h).
void print_ggx_filter(int p_probe_size) {
	const Clock::time_point start = Clock::now();
	const GgxFilter filter(p_probe_size);
	std::printf("  GGX filter for %d^2 faces (built once per size): %d levels, %d samples, %.2f M taps, %.1f MiB, built in %.0f ms\n", p_probe_size,
			filter.level_count(), filter.sample_count(), double(filter.tap_count()) / 1e6, double(filter.memory_bytes()) / 1048576.0, ms_since(start));
}

void print_stage_table(const StepRun &p_run, const LiveRoomStats &p_stats) {
	std::printf("  processed: %zu RGB-D frames, %zu of %zu fisheye frames integrated (%llu skipped without a tracked pose%s%s), %zu unreadable",
			p_run.rgbd_done, p_run.fisheye_integrated, p_run.fisheye_pushed, (unsigned long long)p_stats.fisheye_without_pose,
			p_stats.fisheye_pose_problem.empty() ? "" : ", last: ", p_stats.fisheye_pose_problem.c_str(), p_run.frames_failed);
	std::printf("; %llu probe renders, %llu stage errors%s%s\n\n", (unsigned long long)p_stats.probe_renders, (unsigned long long)p_stats.stage_errors,
			p_stats.last_error.empty() ? "" : ", last: ", p_stats.last_error.c_str());

	print_table_header("per-stage timings, ms (n = frames or calls; paper: Table 1, a GPU system, for reference)");
	char name[96];
	std::snprintf(name, sizeof(name), "re-mesh + placement BVH (every %d fused)", MESH_INTERVAL);
	print_slam_rows(p_run.figures, name);
	print_row("  copy of the changed blocks (SLAM worker)", p_run.figures.mesh_copy);
	print_row("  marching cubes, whole mesh (mesh worker)", p_run.figures.mesh_build);
	print_row("push_rgbd (whole engine call)", p_run.push_rgbd);
	std::printf("  coarse model, per integrated fisheye frame:\n");
	print_row("  undistort fisheye (not needed)", Series(), 8.55, "Undistort fisheye image");
	const bool occlusion_skipped = p_run.occlusion_skipped == p_run.fisheye_integrated && p_run.fisheye_integrated > 0;
	print_row(occlusion_skipped ? "  occlusion (skipped: convex room)" : "  occlusion", p_run.occlusion, 0.61, "Render occlusion mask");
	print_row("  lighting (gain)", p_run.lighting, 21.37, "Estimate brightness");
	print_row("  texture update", p_run.update, 0.29, "Update coarse model");
	print_row("  inpaint compose (async request)", p_run.inpaint);
	print_row("  coarse frame (add_fisheye_frame)", p_run.coarse_frame);
	print_row("  push_fisheye (whole engine call)", p_run.push_fisheye);
	std::printf("  probe %s's environment map, per RGB-D frame (ProbeMap):\n", p_run.setup.probe_from_file ? "0" : "(floorplan centre)");
	print_map_rows(p_run.map,
			{ "  coarse cubemap render %d^2", "  dense cubemap pass %d^2 (scale %d)", "  SH projection", "  GGX chain + half-float mips (6 faces)",
					"  probe map (whole render)" },
			p_run.setup.probe_size, p_run.setup.config.dense_render_scale);
	print_row("  render_probes (whole engine call)", p_run.render_call);
	print_ggx_filter(p_run.setup.probe_size);
	std::printf("  after the last frame: finish (inpainting) %.2f ms, final update_dense_mesh %.2f ms (%zu triangles)\n", p_run.finish_ms, p_run.last_mesh_ms,
			p_run.figures.mesh_triangles);
}

// How the frame's cost and the TSDF's memory grow with the recording: the first tenth against the last.
void print_growth(const Series &p_frame_ms, size_t p_early_bytes, size_t p_final_bytes) {
	const size_t n = p_frame_ms.size(), tenth = std::max<size_t>(1, n / 10);
	if (n < 2) {
		return;
	}
	Series first, last;
	first.values.assign(p_frame_ms.values.begin(), p_frame_ms.values.begin() + long(tenth));
	last.values.assign(p_frame_ms.values.end() - long(tenth), p_frame_ms.values.end());
	std::printf("  growth: push_rgbd + render_probes median %.2f ms over the first %zu frames, %.2f ms over the last %zu; TSDF %.1f MiB a tenth in, %.1f MiB at the end\n",
			first.median(), tenth, last.median(), tenth, double(p_early_bytes) / (1024.0 * 1024.0), double(p_final_bytes) / (1024.0 * 1024.0));
}

FullFrame print_full_frame(const StepRun &p_run) {
	FullFrame full;
	full.fisheye_per_rgbd = double(p_run.fisheye_integrated) / double(p_run.rgbd_done);
	full.median = p_run.live_frame.median() + full.fisheye_per_rgbd * p_run.push_fisheye.median();
	full.mean = p_run.live_frame.mean() + full.fisheye_per_rgbd * p_run.push_fisheye.mean();
	std::printf("\nfull frame = push_rgbd + render_probes (per RGB-D frame) + %.3f integrated fisheye frames per RGB-D frame x push_fisheye:\n",
			full.fisheye_per_rgbd);
	std::printf("  median-based %.2f ms (%.2f + %.3f x %.2f)   mean-based %.2f ms   paper %.2f ms (GPU system, incl. rendering the scene)\n", full.median,
			p_run.live_frame.median(), full.fisheye_per_rgbd, p_run.push_fisheye.median(), full.mean, PAPER_FRAME_MS);
	std::printf("  (re-meshing is inside push_rgbd: in the mean, rarely in the median)\n");
	print_growth(p_run.live_frame, p_run.early_tsdf_bytes, p_run.engine.stats().tsdf.bytes_used);
	if (p_run.setup.synthetic) {
		print_slam_target(p_run.figures, p_run.setup.config.rig.rgb.width, p_run.setup.config.rig.rgb.height);
	}
	return full;
}

// The dense pass's cost options on the final model: the engine's coarse map at the probe
// (render_at without the dense model), then render_dense_over on the engine's TSDF at each scale.
void print_dense_options(LiveRoom *r_engine, const RecordingSetup &p_setup) {
	std::printf("\ndense cubemap options on the final model at probe %s (median of %d):\n", p_setup.probe_from_file ? "0" : "(floorplan centre)",
			OPTION_REPEATS);
	const DenseSlam *slam = r_engine->slam_model();
	const std::array<float, 256> rgb_lut = rgb_radiance_lut(p_setup.config.photometry);
	std::printf("  %-6s %-6s %10s %16s %10s   %s\n", "size", "scale", "ms", "covered texels", "of all", "render_at (coarse + dense, engine's scale), ms");
	for (int size : { 128, 256 }) {
		const Cubemap base = r_engine->render_at(p_setup.probe, size, true, false);
		Series engine_ms;
		for (int repeat = 0; repeat < OPTION_REPEATS; repeat++) {
			const Clock::time_point start = Clock::now();
			const Cubemap whole = r_engine->render_at(p_setup.probe, size, true, true);
			engine_ms.add(ms_since(start));
		}
		for (int scale : { 1, 2, 4 }) {
			DenseRenderOptions options;
			options.scale = scale;
			options.lut = p_setup.config.photometry.known ? &rgb_lut : nullptr;
			Series ms;
			int covered = 0;
			for (int repeat = 0; slam != nullptr && repeat < OPTION_REPEATS; repeat++) {
				Cubemap map = clone_cubemap(base);
				const Clock::time_point start = Clock::now();
				const DenseRenderStats dense = render_dense_over(slam->volume(), p_setup.probe, options, &map);
				ms.add(ms_since(start));
				covered = dense.texels_covered;
			}
			std::printf("  %3d^2  1/%-4d %10.2f %16d %9.1f%%", size, scale, ms.median(), covered, 100.0 * double(covered) / (6.0 * size * size));
			if (scale == p_setup.config.dense_render_scale) {
				std::printf("   %.2f", engine_ms.median());
			}
			std::printf("\n");
		}
	}
}

Accuracy print_accuracy_and_memory(const StepRun &p_run, const LiveRoomStats &p_stats) {
	std::printf("\n");
	const Accuracy accuracy = print_accuracy(p_run.figures.reported, p_run.setup.config.ground_truth, p_run.figures, p_run.setup.synthetic,
			"the engine's tracked RGB-D poses, the held pose when lost");
	if (!p_run.fisheye_error_mm.empty()) {
		std::printf("  fisheye poses from the tracked trajectory: position error median %.2f mm, max %.2f mm (against the ground truth's)\n",
				p_run.fisheye_error_mm.median(), p_run.fisheye_error_mm.percentile(1.0));
	}
	std::printf("\n");
	print_memory(p_stats.tsdf);
	std::printf("  dense mesh: %zu triangles\n", p_run.figures.mesh_triangles);
	return accuracy;
}

// The peers, issue #11's targets and the summary line; 1 when --open3d-results does not fit.
int print_speed(const StepRun &p_run, const FullFrame &p_full, const Accuracy &p_accuracy) {
	const SlamFigures &figures = p_run.figures;
	PeerRatios ratios = p_run.args.peers ? print_opencv_peers(p_run.peer_frames, p_run.setup, figures) : PeerRatios();
	if (!p_run.args.open3d_results.empty() && !read_open3d_peer(p_run.args.open3d_results, p_run.setup, figures, p_run.rgbd_done, &ratios)) {
		return 1;
	}
	SpeedFigures speed;
	speed.tracking_ms = figures.track.median();
	speed.integration_ms = figures.integrate.median();
	speed.raycast_ms = figures.raycast.median();
	speed.coarse_ms = p_run.push_fisheye.median();
	speed.probe_ms = p_run.map.total.median();
	speed.full_frame_ms = p_full.median;
	speed.probe_size = p_run.setup.probe_size;
	print_speed_targets(speed, ratios);
	print_device_batches(p_run.setup.config.compute_backend, p_run.rgbd_done);
	std::printf("summary: mode=slam frames=%zu fisheye_frames=%zu track_ms_p50=%.2f integrate_ms_p50=%.2f slam_ms_p50=%.2f probe_ms_p50=%.2f "
				"frame_ms_p50=%.2f frame_ms_mean=%.2f %s %s %s good=%d poor=%d lost=%d\n",
			p_run.rgbd_done, p_run.fisheye_integrated, figures.track.median(), figures.integrate.median(), figures.process.median(),
			p_run.map.total.median(), p_full.median, p_full.mean, speed_summary(speed, ratios).c_str(), accuracy_summary(p_accuracy).c_str(),
			backend_summary(p_run.setup.config.compute_backend, p_run.engine.stats().compute_on_device).c_str(),
			figures.good, figures.poor, figures.lost);
	return 0;
}

} // namespace

int bench_recording(const Arguments &p_args) {
	RecordingSetup setup;
	if (!open_recording(p_args, STEP_PROBE_SIZE, &setup)) {
		return 1;
	}
	if (!setup.engine_skip.empty()) {
		return bench_dense_recording(p_args, setup);
	}
	StepRun run(p_args, setup);
	if (!start_run(&run)) {
		return 1;
	}
	play(&run);
	if (run.rgbd_done == 0) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no RGB-D frame could be read\n", p_args.recording.c_str());
		return 1;
	}
	const LiveRoomStats stats = run.engine.stats();
	print_stage_table(run, stats);
	const FullFrame full = print_full_frame(run);
	print_dense_options(&run.engine, setup);
	const Accuracy accuracy = print_accuracy_and_memory(run, stats);
	run.trajectory_file.close(p_args.save_trajectory);
	return print_speed(run, full, accuracy);
}

} // namespace roomprobe::bench
