// soak --recording (issue #17): the recording played back and forth (so the camera never jumps)
// through the engine in step mode, with every stage and one probe, for --frames RGB-D frames;
// resident memory and per-frame times sampled as it goes. Timestamps keep increasing: each pass
// starts a frame period after the last.

#include "bench_setup.h"

#include <algorithm>
#include <fstream>
#include <utility>

#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h> // malloc_trim
#endif

namespace roomprobe::bench {

namespace {

// The soak's verdict: resident memory in the last quarter of the run (median) within this share
// over the highest sample of the first quarter after the warm-up (judge_memory), and the time per
// frame of the last tenth at most this factor of the first tenth after the warm-up (medians; the
// time's margin is this machine's noise between two windows of the same work).
constexpr double SOAK_MEMORY_GROWTH_MAX = 0.05;
constexpr double SOAK_TIME_RATIO_MAX = 1.15;
constexpr double SOAK_WARMUP_SHARE = 0.2; // of the frames: the TSDF and the pools reach their size

// The process's resident memory, bytes (/proc/self/statm's second field, in pages).
size_t resident_bytes() {
	std::ifstream statm("/proc/self/statm");
	size_t pages = 0, resident = 0;
	statm >> pages >> resident;
	return resident * size_t(sysconf(_SC_PAGESIZE));
}

// The passes' clock: the recording's span and frame period, and the fisheye's offset.
struct SoakClock {
	double first_s = 0.0, last_s = 0.0, period_s = 0.0;
	double fisheye_offset_s = 0.0; // fisheye clock = RGB-D clock - offset
};

// What the run sampled.
struct SoakRun {
	size_t total = 0, sample_every = 1, warmup = 0;
	Series frame_ms, fisheye_ms, window_ms;
	std::vector<std::pair<size_t, size_t>> rss_samples; // (frame, bytes)
	size_t done = 0, failed = 0, pass = 0;
	uint64_t lost = 0;
};

// The soak's figures against its thresholds.
struct SoakVerdict {
	double rss_warm = 0.0, rss_warm_max = 0.0, rss_late = 0.0, growth = 0.0; // growth: rss_late against rss_warm_max
	size_t rss_max = 0;
	double time_early = 0.0, time_late = 0.0, time_ratio = 0.0;
	bool memory_flat = false, time_flat = false;
};

void soak_rgbd(RgbdFrame &&p_frame, double p_t_s, LiveRoom *r_engine, SoakRun *r_run) {
	p_frame.timestamp_s = p_t_s;
	p_frame.depth_timestamp_s = p_t_s;
	const Clock::time_point start = Clock::now();
	r_engine->push_rgbd(std::move(p_frame));
	r_engine->render_probes();
	const double ms = ms_since(start);
	r_run->frame_ms.add(ms);
	r_run->window_ms.add(ms);
	const std::shared_ptr<const TrackedFrame> tracked = r_engine->tracked_frame();
	r_run->lost += tracked && tracked->state == TrackingState::Lost ? 1 : 0;
	if (++r_run->done % r_run->sample_every == 0 || r_run->done == r_run->total) {
		const size_t rss = resident_bytes();
		r_run->rss_samples.push_back({ r_run->done, rss });
		std::printf("  %8zu %10.1f %10.1f %10.2f %12.2f %8llu\n", r_run->done, double(rss) / 1e6, double(r_engine->stats().tsdf.bytes_used) / 1e6,
				r_run->window_ms.median(), r_run->fisheye_ms.empty() ? 0.0 : r_run->fisheye_ms.median(), (unsigned long long)r_run->lost);
		std::fflush(stdout);
		r_run->window_ms = Series();
	}
}

// One pass over the recording, forwards or backwards, until the run's frames are done.
void soak_pass(const RecordingPlayer &p_player, const SoakClock &p_clock, LiveRoom *r_engine, SoakRun *r_run) {
	const std::vector<PlaybackEvent> &events = p_player.events();
	const bool forward = r_run->pass % 2 == 0;
	const double pass_start_s = double(r_run->pass) * (p_clock.last_s - p_clock.first_s + p_clock.period_s);
	for (size_t k = 0; k < events.size() && r_run->done < r_run->total; k++) {
		SourceFrame frame = p_player.read(forward ? k : events.size() - 1 - k);
		const double t_s = pass_start_s + (forward ? frame.event.time_s - p_clock.first_s : p_clock.last_s - frame.event.time_s);
		if (!frame.ok) {
			r_run->failed++;
		} else if (frame.event.stream == RecordingStream::Rgbd) {
			soak_rgbd(std::move(frame.rgbd), t_s, r_engine, r_run);
		} else {
			frame.fisheye.timestamp_s = t_s - p_clock.fisheye_offset_s;
			const Clock::time_point start = Clock::now();
			r_engine->push_fisheye(std::move(frame.fisheye));
			r_run->fisheye_ms.add(ms_since(start));
		}
	}
	r_run->pass++;
}

// Memory: the median of the samples in the last quarter of the run against the highest sample in
// the first quarter after the warm-up. Resident memory swings by up to 15 % as the allocators'
// pools and the meshing's buffers come and go, and stays in a state for several samples: CI's early
// median once sat at 406 MB in a run whose samples ranged over 406-441 MB with no trend (+5.7 %,
// a false alarm). A swing returns within the range the early run already reached; a leak grows
// past it, and its growth over the judged frames is what the share bounds.
void judge_memory(const SoakRun &p_run, SoakVerdict *r_verdict) {
	const size_t done = p_run.done, warmup = p_run.warmup;
	const size_t window_frames = std::max<size_t>(1, (done - std::min(done, warmup)) / 4);
	Series rss_early, rss_late;
	for (const auto &[frame, bytes] : p_run.rss_samples) {
		if (frame >= warmup) {
			r_verdict->rss_max = std::max(r_verdict->rss_max, bytes);
			if (frame < warmup + window_frames) {
				rss_early.add(double(bytes));
			}
		}
		if (frame + window_frames >= done) {
			rss_late.add(double(bytes));
		}
	}
	if (rss_early.empty() && !p_run.rss_samples.empty()) { // a short run: the first sample after the warm-up
		const auto first = std::find_if(p_run.rss_samples.begin(), p_run.rss_samples.end(), [&](const auto &p_sample) { return p_sample.first >= warmup; });
		rss_early.add(double(first != p_run.rss_samples.end() ? first->second : p_run.rss_samples.back().second));
	}
	r_verdict->rss_warm = rss_early.median();
	r_verdict->rss_warm_max = rss_early.empty() ? 0.0 : *std::max_element(rss_early.values.begin(), rss_early.values.end());
	r_verdict->rss_late = rss_late.median();
	r_verdict->growth = r_verdict->rss_warm_max > 0.0 ? r_verdict->rss_late / r_verdict->rss_warm_max - 1.0 : 0.0;
	r_verdict->memory_flat = r_verdict->growth <= SOAK_MEMORY_GROWTH_MAX;
}

// Time: the median of the first tenth after the warm-up against the last tenth's.
void judge_time(const SoakRun &p_run, SoakVerdict *r_verdict) {
	const Series &frame_ms = p_run.frame_ms;
	const size_t tenth = std::max<size_t>(1, (frame_ms.size() - std::min(frame_ms.size(), p_run.warmup)) / 10);
	Series early, late;
	for (size_t i = 0; i < frame_ms.size(); i++) {
		if (i >= p_run.warmup && i < p_run.warmup + tenth) {
			early.add(frame_ms.values[i]);
		}
		if (i + tenth >= frame_ms.size()) {
			late.add(frame_ms.values[i]);
		}
	}
	r_verdict->time_early = early.median();
	r_verdict->time_late = late.median();
	r_verdict->time_ratio = r_verdict->time_early > 0.0 ? r_verdict->time_late / r_verdict->time_early : 0.0;
	r_verdict->time_flat = r_verdict->time_ratio <= SOAK_TIME_RATIO_MAX;
}

void print_verdict(const SoakRun &p_run, const SoakVerdict &p_verdict, size_t p_rss_start, size_t p_rss_after, size_t p_rss_trimmed) {
	const SoakVerdict &v = p_verdict;
	std::printf("\n  %zu passes over the recording; %zu frames unreadable; %llu of %zu frames lost to tracking\n", p_run.pass, p_run.failed,
			(unsigned long long)p_run.lost, p_run.done);
	std::printf("  resident memory: %.1f MB median, %.1f MB highest in the first quarter after the warm-up (%zu frames); %.1f MB median in "
				"the last quarter: %+.2f %% over the early highest (at most %+.0f %%): %s; %.1f MB at the start, at most %.1f MB after the warm-up\n",
			v.rss_warm / 1e6, v.rss_warm_max / 1e6, p_run.warmup, v.rss_late / 1e6, 100.0 * v.growth, 100.0 * SOAK_MEMORY_GROWTH_MAX,
			v.memory_flat ? "flat" : "GROWS", double(p_rss_start) / 1e6, double(v.rss_max) / 1e6);
	std::printf("  time per frame (push and probe map), medians: %.2f ms in the first tenth after the warm-up, %.2f ms in the last: x%.3f "
				"(at most x%.2f): %s\n",
			v.time_early, v.time_late, v.time_ratio, SOAK_TIME_RATIO_MAX, v.time_flat ? "flat" : "GROWS");
	std::printf("  after the engine is destroyed: %.1f MB resident, %.1f MB once the allocator gave back what it kept for reuse (malloc_trim; leaks at "
				"exit: ./roomprobe soak --sanitize address)\n",
			double(p_rss_after) / 1e6, double(p_rss_trimmed) / 1e6);
	std::printf("summary: mode=soak frames=%zu rss_early_mb=%.1f rss_early_max_mb=%.1f rss_late_mb=%.1f rss_max_mb=%.1f rss_growth_pct=%.2f "
				"frame_ms_early=%.2f frame_ms_late=%.2f time_ratio=%.3f lost=%llu unreadable=%zu flat=%s\n",
			p_run.done, v.rss_warm / 1e6, v.rss_warm_max / 1e6, v.rss_late / 1e6, double(v.rss_max) / 1e6, 100.0 * v.growth, v.time_early, v.time_late, v.time_ratio,
			(unsigned long long)p_run.lost, p_run.failed, v.memory_flat && v.time_flat ? "yes" : "no");
}

} // namespace

int bench_soak(const Arguments &p_args) {
	Arguments all_frames = p_args;
	all_frames.frames = -1; // --frames counts the soak's frames, not the recording's
	RecordingSetup setup;
	if (!open_recording(all_frames, STEP_PROBE_SIZE, &setup)) {
		return 1;
	}
	if (!setup.engine_skip.empty()) {
		std::fprintf(stderr, "roomprobe_bench: soak --recording %s: %s; the soak runs every stage\n", p_args.recording.c_str(), setup.engine_skip.c_str());
		return 1;
	}
	const RecordingReader &reader = setup.reader();
	const std::vector<PlaybackEvent> &events = setup.player.events();
	SoakClock clock;
	clock.first_s = events.front().time_s;
	clock.last_s = events.back().time_s;
	clock.period_s = std::max(1e-3, (clock.last_s - clock.first_s) / double(std::max<size_t>(1, reader.rgbd_count())));
	clock.fisheye_offset_s = setup.config.rig.fisheye_time_offset_s;
	setup.config.ground_truth = Trajectory(); // its timestamps no longer match: poses are tracked anyway
	SoakRun run;
	run.total = p_args.frames > 0 ? size_t(p_args.frames) : 50000;
	run.sample_every = std::max<size_t>(1, run.total / 100);
	run.warmup = p_args.warmup_frames > 0 ? std::min(run.total - 1, size_t(p_args.warmup_frames))
										  : std::max<size_t>(1, size_t(SOAK_WARMUP_SHARE * double(run.total)));

	std::printf("roomprobe_bench soak --recording %s\n", p_args.recording.c_str());
	std::printf("  %zu RGB-D frames: the recording's %zu RGB-D and %zu fisheye frames back and forth, every stage, one %d^2 probe\n", run.total,
			reader.rgbd_count(), reader.fisheye_count(), setup.probe_size);
	std::printf("  %8s %10s %10s %10s %12s %8s\n", "frame", "rss_MB", "tsdf_MB", "frame_ms", "fisheye_ms", "lost");
	const size_t rss_start = resident_bytes();
	{
		LiveRoom engine;
		if (!configure_engine(setup, "soak --recording " + p_args.recording, &engine)) {
			return 1;
		}
		engine.add_probe(setup.probe, setup.probe_size);
		while (run.done < run.total) {
			soak_pass(setup.player, clock, &engine, &run);
		}
		engine.finish();
	}
	const size_t rss_after = resident_bytes();
#ifdef __GLIBC__
	// What of that the allocator only keeps for reuse: glibc's arenas hold freed memory of the
	// engine's threads until trimmed. The rest is still held by something.
	malloc_trim(0);
	const size_t rss_trimmed = resident_bytes();
#else
	const size_t rss_trimmed = rss_after;
#endif
	SoakVerdict verdict;
	judge_memory(run, &verdict);
	judge_time(run, &verdict);
	print_verdict(run, verdict, rss_start, rss_after, rss_trimmed);
	return verdict.memory_flat && verdict.time_flat && run.failed == 0 ? 0 : 1;
}

} // namespace roomprobe::bench
