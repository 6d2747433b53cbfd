// live --recording: the engine threaded (start()), the recording played in real time by a
// PacedPlayer (its thread reads each frame when its instant comes and pushes it), the probe map
// polled by a main loop as Godot's (bench_main.cpp says what is printed).

#include "bench_setup.h"

#include <source/paced_player.h>

#include <array>
#include <atomic>
#include <cstring>
#include <thread>

namespace roomprobe::bench {

namespace {

// Godot's main loop, as the live benchmark polls the engine.
constexpr double MAIN_LOOP_HZ = 60.0;
// After finish(): how long the main loop waits for the probe map that includes the last frames.
constexpr double FINAL_MAP_WAIT_S = 2.0;

Clock::duration duration_of(double p_s) {
	return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(p_s));
}

// The recording time played: the first event to the last.
double span_s(const RecordingPlayer &p_player) {
	return p_player.events().back().time_s - p_player.events().front().time_s;
}

// The capture thread's figures: written on the player's thread, read once it is stopped.
struct CaptureFigures {
	Series late_ms, decode_rgbd_ms, decode_fisheye_ms, push_call_ms;
	size_t rgbd_pushed = 0, fisheye_pushed = 0, frames_failed = 0;
	std::atomic<bool> done{ false };
	Clock::time_point end;
};

// A frame as a device driver delivers it, pushed as RigCapture pushes it.
void capture_frame(SourceFrame &&p_frame, LiveRoom *r_engine, CaptureFigures *r_capture) {
	const bool rgbd = p_frame.event.stream == RecordingStream::Rgbd;
	r_capture->late_ms.add(p_frame.late_ms);
	(rgbd ? r_capture->decode_rgbd_ms : r_capture->decode_fisheye_ms).add(p_frame.read_ms);
	if (!p_frame.ok) {
		r_capture->frames_failed++;
		return;
	}
	const Clock::time_point push_start = Clock::now();
	if (rgbd) {
		r_engine->push_rgbd(std::move(p_frame.rgbd));
	} else {
		r_engine->push_fisheye(std::move(p_frame.fisheye));
	}
	r_capture->push_call_ms.add(ms_since(push_start));
	(rgbd ? r_capture->rgbd_pushed : r_capture->fisheye_pushed)++;
}

// The main thread, as Godot's: each tick takes the newest map and, when it is new, copies its
// faces' bytes (as into the Image the ReflectionProbe's texture is made from).
struct MainLoop {
	Series copy_ms, poll_ms;
	MapSeries map;
	Series slam_track, slam_integrate, slam_frame, coarse_frame;
	std::array<std::vector<uint8_t>, 6> face_bytes;
	uint64_t map_version_seen = 0, tracked_seen = 0, coarse_seen = 0;
	std::shared_ptr<const ProbeMap> map_taken; // its faces are uploaded; a face it shares is not copied again
	size_t ticks = 0, late_ticks = 0, maps_taken = 0;
	bool final_map_seen = false;
	double finish_ms = 0.0;
	Clock::time_point end;
};

// What the map with the last frames must include, as the engine stood at finish().
struct FinalFrames {
	uint64_t rgbd = 0, fisheye = 0, version_at_finish = 0;
};

// The newest map; a new one's faces copied.
std::shared_ptr<const ProbeMap> poll_map(const LiveRoom &p_engine, int p_probe_id, MainLoop *r_loop) {
	const Clock::time_point poll_start = Clock::now();
	const std::shared_ptr<const ProbeMap> map = p_engine.probe_map(p_probe_id);
	if (!map || map->version == r_loop->map_version_seen) {
		r_loop->poll_ms.add(ms_since(poll_start));
		return map;
	}
	for (size_t f = 0; f < 6; f++) {
		if (r_loop->map_taken && r_loop->map_taken->gpu_faces[f] == map->gpu_faces[f]) {
			continue; // as RoomProbe: an unchanged face is not uploaded
		}
		const PixelBuffer &src = *map->gpu_faces[f];
		r_loop->face_bytes[f].resize(src.size());
		std::memcpy(r_loop->face_bytes[f].data(), src.data(), src.size());
	}
	r_loop->copy_ms.add(ms_since(poll_start));
	r_loop->map_version_seen = map->version;
	r_loop->map_taken = map;
	r_loop->maps_taken++;
	r_loop->map.add(*map);
	return map;
}

// The stages' own timings, as often as the main loop sees a new result.
void take_stage_timings(const LiveRoom &p_engine, MainLoop *r_loop) {
	if (const std::shared_ptr<const TrackedFrame> tracked = p_engine.tracked_frame(); tracked && tracked->sequence != r_loop->tracked_seen) {
		r_loop->tracked_seen = tracked->sequence;
		r_loop->slam_track.add(tracked->timings.track_ms);
		if (tracked->integrated) {
			r_loop->slam_integrate.add(tracked->timings.integrate_ms);
		}
		r_loop->slam_frame.add(tracked->timings.frame_ms);
	}
	if (const std::shared_ptr<const CoarseSnapshot> snapshot = p_engine.coarse_snapshot(); snapshot && snapshot->frames != r_loop->coarse_seen) {
		r_loop->coarse_seen = snapshot->frames;
		r_loop->coarse_frame.add(snapshot->timings.frame_ms);
	}
}

// The recording is over: the engine finishes what it was given (the main thread waits, as a
// node's finish would).
FinalFrames finish_engine(LiveRoom *r_engine, int p_probe_id, MainLoop *r_loop) {
	const Clock::time_point finish_start = Clock::now();
	r_engine->finish();
	r_loop->finish_ms = ms_since(finish_start);
	const std::shared_ptr<const TrackedFrame> last_tracked = r_engine->tracked_frame();
	const std::shared_ptr<const CoarseSnapshot> last_coarse = r_engine->coarse_snapshot();
	const std::shared_ptr<const ProbeMap> at_finish = r_engine->probe_map(p_probe_id);
	FinalFrames final_frames;
	final_frames.rgbd = last_tracked ? last_tracked->sequence : 0;
	final_frames.fisheye = last_coarse ? last_coarse->fisheye_sequence : 0;
	final_frames.version_at_finish = at_finish ? at_finish->version : 0;
	return final_frames;
}

// Ticks at MAIN_LOOP_HZ from p_start until, after the capture ended and the engine finished, a
// map made after that includes the last frames of both streams (or FINAL_MAP_WAIT_S passed).
void run_main_loop(LiveRoom *r_engine, int p_probe_id, PacedPlayer *r_capture_player, const CaptureFigures &p_capture, Clock::time_point p_start,
		MainLoop *r_loop) {
	bool draining = false;
	Clock::time_point drain_deadline = p_start;
	FinalFrames final_frames;
	const Clock::duration tick = duration_of(1.0 / MAIN_LOOP_HZ);
	Clock::time_point next_tick = p_start;
	while (true) {
		std::this_thread::sleep_until(next_tick);
		next_tick += tick;
		if (Clock::now() > next_tick) {
			r_loop->late_ticks++;
			next_tick = Clock::now() + tick; // a missed frame is not caught up
		}
		r_loop->ticks++;
		const std::shared_ptr<const ProbeMap> map = poll_map(*r_engine, p_probe_id, r_loop);
		take_stage_timings(*r_engine, r_loop);
		if (!draining && p_capture.done) {
			r_capture_player->stop();
			final_frames = finish_engine(r_engine, p_probe_id, r_loop);
			draining = true;
			drain_deadline = Clock::now() + duration_of(FINAL_MAP_WAIT_S);
			continue;
		}
		if (draining) {
			const bool final_map = map && map->version > final_frames.version_at_finish && map->rgbd_sequence >= final_frames.rgbd &&
					map->fisheye_sequence >= final_frames.fisheye;
			r_loop->final_map_seen = final_map;
			if (final_map || Clock::now() > drain_deadline) {
				break;
			}
		}
	}
	r_loop->end = Clock::now();
}

void print_frames(const LiveRoomStats &p_stats, const CaptureFigures &p_capture) {
	const LiveRoomStats &stats = p_stats;
	std::printf("  pushed: %zu RGB-D, %zu fisheye frames; %zu unreadable\n\n", p_capture.rgbd_pushed, p_capture.fisheye_pushed, p_capture.frames_failed);
	std::printf("frames (LiveRoomStats):\n");
	std::printf("  RGB-D:   pushed %llu, processed %llu, dropped %llu (%.1f%%)\n", (unsigned long long)stats.rgbd_pushed,
			(unsigned long long)stats.rgbd_processed, (unsigned long long)stats.rgbd_dropped,
			stats.rgbd_pushed == 0 ? 0.0 : 100.0 * double(stats.rgbd_dropped) / double(stats.rgbd_pushed));
	std::printf("  fisheye: pushed %llu, integrated %llu, dropped %llu (%.1f%%), without a pose %llu%s%s\n", (unsigned long long)stats.fisheye_pushed,
			(unsigned long long)stats.fisheye_integrated, (unsigned long long)stats.fisheye_dropped,
			stats.fisheye_pushed == 0 ? 0.0 : 100.0 * double(stats.fisheye_dropped) / double(stats.fisheye_pushed),
			(unsigned long long)stats.fisheye_without_pose, stats.fisheye_pose_problem.empty() ? "" : " (last: ", stats.fisheye_pose_problem.empty() ? "" : (stats.fisheye_pose_problem + ")").c_str());
	std::printf("  dense SLAM: %zu frames, %zu fused; stage errors %llu%s%s\n", stats.dense_frames, stats.dense_fused,
			(unsigned long long)stats.stage_errors, stats.last_error.empty() ? "" : ", last: ", stats.last_error.c_str());
	std::printf("latency, push to the first probe map that includes the frame (nearest rank):\n");
	std::printf("  RGB-D:   n %zu   p50 %.2f ms   p95 %.2f ms   max %.2f ms\n", stats.rgbd_latency.count, stats.rgbd_latency.p50_ms,
			stats.rgbd_latency.p95_ms, stats.rgbd_latency.max_ms);
	std::printf("  fisheye: n %zu   p50 %.2f ms   p95 %.2f ms   max %.2f ms\n", stats.fisheye_latency.count, stats.fisheye_latency.p50_ms,
			stats.fisheye_latency.p95_ms, stats.fisheye_latency.max_ms);
}

void print_timings(const MainLoop &p_loop, const LiveRoomStats &p_stats, int p_probe_size, int p_dense_render_scale) {
	std::printf("\n");
	print_table_header("timings, ms (the workers' published figures, each as often as the main loop saw a new one)");
	print_row("SLAM tracking", p_loop.slam_track);
	print_row("SLAM integration (fused frames)", p_loop.slam_integrate);
	print_row("SLAM process (whole call)", p_loop.slam_frame, 3.16, "SLAM Update (GPU)");
	print_row("coarse frame (add_fisheye_frame)", p_loop.coarse_frame);
	print_map_rows(p_loop.map,
			{ "probe coarse cubemap %d^2", "probe dense pass %d^2 (scale %d)", "probe SH projection", "probe GGX chain + half-float mips",
					"probe map (whole render)" },
			p_probe_size, p_dense_render_scale);
	std::printf("  probe renders: %llu by the engine, %zu taken by the main loop\n", (unsigned long long)p_stats.probe_renders, p_loop.maps_taken);
	std::printf("main thread (%zu ticks at %.0f Hz, %zu late):\n", p_loop.ticks, MAIN_LOOP_HZ, p_loop.late_ticks);
	size_t map_bytes = 0;
	for (const std::vector<uint8_t> &face : p_loop.face_bytes) {
		map_bytes += face.size();
	}
	const Series &copy = p_loop.copy_ms;
	std::printf("  take a new map + copy its GPU bytes (%.2f MiB, 6 faces with mips): n %zu   p50 %.3f ms   p95 %.3f ms   max %.3f ms\n",
			double(map_bytes) / (1024.0 * 1024.0), copy.size(), copy.median(), copy.percentile(0.95), copy.percentile(1.0));
	std::printf("  poll without a new map: n %zu   p50 %.4f ms   p95 %.4f ms\n", p_loop.poll_ms.size(), p_loop.poll_ms.median(), p_loop.poll_ms.percentile(0.95));
}

// The capture thread's rows and the real-time factor (returned).
double print_capture(const CaptureFigures &p_capture, const MainLoop &p_loop, Clock::time_point p_start, double p_span_s, double p_speed) {
	const double capture_s = ms_between(p_start, p_capture.end) / 1000.0;
	const double wall_s = ms_between(p_start, p_loop.end) / 1000.0;
	std::printf("capture thread:\n");
	print_row("read + decode RGB-D", p_capture.decode_rgbd_ms);
	print_row("read + decode fisheye", p_capture.decode_fisheye_ms);
	print_row("push call", p_capture.push_call_ms);
	print_row("lateness against the event's instant", p_capture.late_ms);
	std::printf("real time: %.2f s of recording played in %.2f s (capture; x%.2f asked), %.2f s to %s; finish() %.2f ms\n", p_span_s, capture_s, p_speed,
			wall_s, p_loop.final_map_seen ? "the map with the last frames" : "giving up on a map with the last frames", p_loop.finish_ms);
	const double real_time_factor = capture_s > 0.0 ? p_span_s / capture_s : 0.0;
	std::printf("  real-time factor (recording time / capture time): %.3f\n", real_time_factor);
	return real_time_factor;
}

void print_summary(const LiveRoomStats &p_stats, ComputeBackend p_backend, const MainLoop &p_loop, double p_real_time_factor, const Accuracy &p_accuracy) {
	const LiveRoomStats &stats = p_stats;
	const bool has_rgbd_latency = stats.rgbd_latency.count > 0, has_fisheye_latency = stats.fisheye_latency.count > 0;
	std::printf("summary: mode=live latency_ms_p50=%s latency_ms_p95=%s fisheye_latency_ms_p50=%s fisheye_latency_ms_p95=%s dropped_rgbd=%llu "
				"dropped_fisheye=%llu fisheye_without_pose=%llu pushed_rgbd=%llu pushed_fisheye=%llu processed_rgbd=%llu integrated_fisheye=%llu "
				"probe_renders=%llu probe_ms_p50=%s main_copy_ms_p50=%.3f main_copy_ms_p95=%.3f real_time_factor=%.3f %s %s good=%llu "
				"poor=%llu lost=%llu\n",
			figure(has_rgbd_latency, stats.rgbd_latency.p50_ms).c_str(), figure(has_rgbd_latency, stats.rgbd_latency.p95_ms).c_str(),
			figure(has_fisheye_latency, stats.fisheye_latency.p50_ms).c_str(), figure(has_fisheye_latency, stats.fisheye_latency.p95_ms).c_str(),
			(unsigned long long)stats.rgbd_dropped, (unsigned long long)stats.fisheye_dropped, (unsigned long long)stats.fisheye_without_pose,
			(unsigned long long)stats.rgbd_pushed, (unsigned long long)stats.fisheye_pushed, (unsigned long long)stats.rgbd_processed,
			(unsigned long long)stats.fisheye_integrated, (unsigned long long)stats.probe_renders, figure(!p_loop.map.total.empty(), p_loop.map.total.median()).c_str(),
			p_loop.copy_ms.median(), p_loop.copy_ms.percentile(0.95), p_real_time_factor, accuracy_summary(p_accuracy).c_str(),
			backend_summary(p_backend, stats.compute_on_device).c_str(),
			(unsigned long long)stats.good, (unsigned long long)stats.poor, (unsigned long long)stats.lost);
}

// What the run printed after the main loop ended and the engine stopped.
void print_results(const Arguments &p_args, const RecordingSetup &p_setup, const LiveRoom &p_engine, const CaptureFigures &p_capture,
		const MainLoop &p_loop, Clock::time_point p_start) {
	const LiveRoomStats stats = p_engine.stats();
	// ATE over the tracked trajectory (the poses the fisheye takes; Lost frames have none).
	SlamFigures figures;
	figures.good = int(stats.good);
	figures.poor = int(stats.poor);
	figures.lost = int(stats.lost);
	const Trajectory tracked = p_engine.trajectory();
	const std::shared_ptr<const TrackedFrame> last = p_engine.tracked_frame();
	print_frames(stats, p_capture);
	print_timings(p_loop, stats, p_setup.probe_size, p_setup.config.dense_render_scale);
	const double real_time_factor = print_capture(p_capture, p_loop, p_start, span_s(p_setup.player), p_args.speed);
	if (last) {
		std::printf("  last tracked frame: #%llu, %s%s%s\n", (unsigned long long)last->sequence, tracking_state_name(last->state), last->reason.empty() ? "" : ": ",
				last->reason.c_str());
	}
	std::printf("\n");
	const Accuracy accuracy = print_accuracy(tracked, p_setup.config.ground_truth, figures, p_setup.synthetic, "the tracked trajectory, whose poses lost frames do not enter");
	std::printf("\n");
	print_memory(stats.tsdf);
	print_summary(stats, p_setup.config.compute_backend, p_loop, real_time_factor, accuracy);
}

} // namespace

int bench_live(const Arguments &p_args) {
	RecordingSetup setup;
	if (!open_recording(p_args, LIVE_PROBE_SIZE, &setup)) {
		return 1;
	}
	if (!setup.engine_skip.empty()) {
		std::fprintf(stderr, "roomprobe_bench: live --recording %s: %s, so no engine to play it into (slam runs dense SLAM alone on it)\n",
				p_args.recording.c_str(), setup.engine_skip.c_str());
		return 1;
	}
	LiveRoom engine;
	if (!configure_engine(setup, "--recording " + p_args.recording, &engine)) {
		return 1;
	}
	const int probe_id = engine.add_probe(setup.probe, setup.probe_size);
	print_recording_header("live", p_args, setup, engine);

	// The player's events stop before the RGB-D event after the last one wanted (--frames).
	const std::vector<PlaybackEvent> &events = setup.player.events();
	if (events.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no events to play\n", p_args.recording.c_str());
		return 1;
	}
	std::printf("  playback: %zu events over %.2f s of recording at speed %.2f; main loop polls at %.0f Hz\n", events.size(), span_s(setup.player),
			p_args.speed, MAIN_LOOP_HZ);
	if (!engine.start()) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: the engine did not start\n", p_args.recording.c_str());
		return 1;
	}

	// The capture thread: every frame in time order on the wall clock (x --speed), none dropped.
	CaptureFigures capture;
	PacedPlayer capture_player(setup.player);
	PacedOptions pacing;
	pacing.clock = PaceClock::Wall;
	pacing.speed = p_args.speed;
	pacing.drop = DropPolicy::None;
	pacing.on_end = [&capture] {
		capture.end = Clock::now();
		capture.done = true;
	};
	const Clock::time_point start = Clock::now();
	capture.end = start;
	capture_player.start(pacing, [&engine, &capture](SourceFrame &&p_frame) { capture_frame(std::move(p_frame), &engine, &capture); });
	MainLoop loop;
	run_main_loop(&engine, probe_id, &capture_player, capture, start, &loop);
	engine.stop();
	print_results(p_args, setup, engine, capture, loop, start);
	return 0;
}

} // namespace roomprobe::bench
