// roomprobe_record: records the live rig into a RoomProbe recording (docs/recording-format.md),
// without Godot: one capture thread per device (capture/device_capture.h) stamping frames on the
// rig's one monotonic clock, and a writer thread behind a bounded queue (recording_queue.h).
//
// usage: roomprobe_record --rig FILE --out DIR [--seconds S] [--rgbd URI] [--fisheye ID]
//          [--fisheye-backend aravis|uvc] [--no-rgbd] [--no-fisheye] [--fake]
//          [--rgbd-latency-ms MS] [--fisheye-latency-ms MS] [--frame-format zstd|png]
//   --frame-format    how RGB, depth and 8-bit fisheye frames are stored: zstd (default: raw frames,
//                     zstd-compressed, fast to decode) or png (docs/recording-format.md)
//   --*-latency-ms    override the rig file's rgbd_latency_s / fisheye_latency_s (calib/README.md)
//   --rgbd URI        an OpenNI2 URI or an .oni file (default: the first depth camera found)
//   --fisheye ID      an Aravis id or IP, or for uvc /dev/videoN, N or a video file (default: the first found)
//   --fake            the first-found Aravis search may take Aravis' Fake camera (a test without hardware)
// A live progress line shows while it records; Ctrl-C stops it cleanly. Both streams are on one
// clock, so the recording's rig.yaml has fisheye_time_offset_s 0. The last line is a summary; its
// *_host_ms_p50/p95 are the host's part of the capture latency (driver hand-over to the sink).
// Relative paths are relative to the folder it is started in: they are made absolute before any
// driver starts (OpenNI2 changes the working directory to its drivers' folder).

#include "../common/cli.h"

#include "capture/capture_clock.h"
#include "capture/live_rig.h"
#include "engine/live_room.h"


#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

using namespace roomprobe;

namespace {

std::atomic<bool> interrupted{ false };

void on_interrupt(int) {
	interrupted = true;
}

// --seconds: finite, at most a day (issue #38: "inf" was taken); Ctrl-C stops sooner.
constexpr double MAX_SECONDS = 86400.0;

// p_path made absolute against the working directory now, before OpenNI2 changes it (a relative
// --out once recorded into OpenNI2's drivers' folder).
std::string absolute_path(const std::string &p_path) {
	std::error_code ec;
	const std::filesystem::path path = std::filesystem::absolute(p_path, ec);
	return ec || p_path.empty() ? p_path : path.lexically_normal().string();
}

// --rgbd and --fisheye name a device or a file (an .oni, a video): only a file's path is made absolute.
std::string absolute_if_file(const std::string &p_value) {
	std::error_code ec;
	return std::filesystem::is_regular_file(p_value, ec) ? absolute_path(p_value) : p_value;
}

int usage_error(const std::string &p_message) {
	std::fprintf(stderr, "roomprobe_record: %s\nusage: roomprobe_record --rig FILE --out DIR [--seconds S] [--rgbd URI] [--fisheye ID] "
						 "[--fisheye-backend aravis|uvc] [--no-rgbd] [--no-fisheye] [--fake] [--rgbd-latency-ms MS] [--fisheye-latency-ms MS]\n"
						 "  [--frame-format zstd|png]  how RGB, depth and 8-bit fisheye frames are stored: zstd (default: raw frames,\n"
						 "                             zstd-compressed, fast to decode) or png (docs/recording-format.md)\n",
			p_message.c_str());
	return 2;
}

// The command line, as given.
struct RecordArgs {
	std::string rig_path, out, rgbd_uri, fisheye_id, backend = "aravis";
	double seconds = 0.0, rgbd_latency_ms = -1.0, fisheye_latency_ms = -1.0; // < 0: the rig file's
	bool use_rgbd = true, use_fisheye = true, fake = false;
	RecordingQueueOptions recording_options;
};

// The command line into *r_args: the exit status when it is refused, else nothing.
std::optional<int> parse_arguments(int p_argc, char **p_argv, RecordArgs *r_args) {
	cli::Arguments args(p_argc, p_argv, 1);
	std::string arg;
	while (args.next(&arg)) {
		if (arg == "--rig") {
			if (!args.value(&r_args->rig_path)) {
				return usage_error("--rig needs a file");
			}
		} else if (arg == "--out") {
			if (!args.value(&r_args->out)) {
				return usage_error("--out needs a folder");
			}
		} else if (arg == "--seconds") {
			if (!args.positive_number(MAX_SECONDS, &r_args->seconds)) {
				return usage_error("--seconds needs a number of seconds in (0, " + std::to_string(long(MAX_SECONDS)) + "]");
			}
		} else if (arg == "--rgbd") {
			if (!args.value(&r_args->rgbd_uri)) {
				return usage_error("--rgbd needs an OpenNI2 URI or .oni file");
			}
		} else if (arg == "--fisheye") {
			if (!args.value(&r_args->fisheye_id)) {
				return usage_error("--fisheye needs a device id");
			}
		} else if (arg == "--fisheye-backend") {
			if (!args.value(&r_args->backend) || (r_args->backend != "aravis" && r_args->backend != "uvc")) {
				return usage_error("--fisheye-backend is aravis or uvc");
			}
		} else if (arg == "--rgbd-latency-ms" || arg == "--fisheye-latency-ms") {
			double &latency = arg == "--rgbd-latency-ms" ? r_args->rgbd_latency_ms : r_args->fisheye_latency_ms;
			if (!args.non_negative_number(&latency) || latency > 1000.0) {
				return usage_error(arg + " needs a number of milliseconds within 0 to 1000");
			}
		} else if (arg == "--frame-format") {
			std::string format;
			if (!args.value(&format) || !parse_frame_format(format, &r_args->recording_options.write.frame_format)) {
				return usage_error("--frame-format needs zstd or png, got '" + format + "'");
			}
		} else if (arg == "--no-rgbd") {
			r_args->use_rgbd = false;
		} else if (arg == "--no-fisheye") {
			r_args->use_fisheye = false;
		} else if (arg == "--fake") {
			r_args->fake = true;
		} else {
			return usage_error("unknown argument '" + arg + "'");
		}
	}
	if (r_args->rig_path.empty() || r_args->out.empty()) {
		return usage_error("--rig and --out are needed");
	}
	return std::nullopt;
}

// The rig file into *r_rig, with the latencies the command line overrides; the exit status when it
// does not load, else nothing.
std::optional<int> load_recording_rig(const RecordArgs &p_args, Rig *r_rig) {
	RigLoadResult loaded = load_rig(p_args.rig_path);
	if (!loaded.ok) {
		std::fprintf(stderr, "roomprobe_record: %s\n", loaded.error.c_str());
		return 1;
	}
	*r_rig = loaded.rig;
	if (p_args.rgbd_latency_ms >= 0.0) {
		r_rig->rgbd_latency_s = p_args.rgbd_latency_ms * 1e-3;
	}
	if (p_args.fisheye_latency_ms >= 0.0 && r_rig->has_fisheye()) {
		r_rig->fisheye_latency_s = p_args.fisheye_latency_ms * 1e-3;
	}
	return std::nullopt;
}

// The devices the command line asks for.
drivers::LiveRigSettings live_settings(const RecordArgs &p_args) {
	drivers::LiveRigSettings settings;
	settings.use_rgbd = p_args.use_rgbd;
	settings.use_fisheye = p_args.use_fisheye;
	settings.rgbd.uri = p_args.rgbd_uri;
	settings.fisheye.device = p_args.fisheye_id;
	settings.fisheye.include_fake = p_args.fake;
	settings.fisheye_backend = p_args.backend == "uvc" ? drivers::FisheyeBackend::Uvc : drivers::FisheyeBackend::Aravis;
	return settings;
}

// The host's part of the capture latency, per stream (RGB-D, fisheye): from the driver handing a
// frame over to the frame, converted and recorded, reaching the engine's sink (the device's own
// part, exposure to hand-over, needs the hardware: the rig file's *_latency_s).
struct HostLatency {
	std::mutex mutex;
	std::vector<double> ms[2];
};

// The progress line every 250 ms, each device's change of state above it, until Ctrl-C, the
// recording fails or p_seconds (> 0) have passed.
void show_progress(const drivers::LiveRig &p_live, double p_seconds) {
	const auto start = std::chrono::steady_clock::now();
	const RecordingStream streams[2] = { RecordingStream::Rgbd, RecordingStream::Fisheye };
	std::string shown_states[2];
	while (!interrupted) {
		std::this_thread::sleep_for(std::chrono::milliseconds(250));
		const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		const RecordingQueueStatus status = p_live.recording_status();
		std::string states;
		for (int i = 0; i < 2; i++) {
			if (!p_live.uses(streams[i])) {
				continue;
			}
			const drivers::DeviceStatus device = p_live.status(streams[i]);
			states += (states.empty() ? "" : ", ") + std::string(drivers::device_state_name(device.state));
			const std::string line = p_live.device_name(streams[i]) + ": " + drivers::device_state_name(device.state) + (device.reason.empty() ? "" : " (" + device.reason + ")");
			if (line != shown_states[i]) {
				std::printf("\n  %s\n", line.c_str()); // each change of state once, above the progress line
				shown_states[i] = line;
			}
		}
		std::printf("\r  %6.1f s  rgbd %llu written %llu dropped  fisheye %llu written %llu dropped  queued %zu  %.1f MB/s  [%s]   ", elapsed,
				(unsigned long long)status.written[0], (unsigned long long)status.dropped[0], (unsigned long long)status.written[1],
				(unsigned long long)status.dropped[1], status.queued, status.megabytes_per_s, states.c_str());
		std::fflush(stdout);
		if (!status.error.empty() || (p_seconds > 0.0 && elapsed >= p_seconds)) {
			break;
		}
	}
	std::printf("\n");
}

// The last line: what was written and dropped, and the host's latency.
void print_summary(const std::string &p_out, const RecordingQueueStatus &p_status, const HostLatency &p_host, bool p_ok) {
	const RecordingQueueStatus &status = p_status;
	const LatencySummary rgbd_host = summarise_latency(p_host.ms[0]);
	const LatencySummary fisheye_host = summarise_latency(p_host.ms[1]);
	std::printf("summary: out=%s seconds=%.2f rgbd_written=%llu rgbd_dropped=%llu fisheye_written=%llu fisheye_dropped=%llu gaps=%llu megabytes=%.1f megabytes_per_s=%.2f "
				"rgbd_host_ms_p50=%.2f rgbd_host_ms_p95=%.2f fisheye_host_ms_p50=%.2f fisheye_host_ms_p95=%.2f ok=%d\n",
			p_out.c_str(), status.seconds, (unsigned long long)status.written[0], (unsigned long long)status.dropped[0],
			(unsigned long long)status.written[1], (unsigned long long)status.dropped[1], (unsigned long long)status.gaps,
			status.megabytes_written, status.megabytes_per_s, rgbd_host.p50_ms, rgbd_host.p95_ms, fisheye_host.p50_ms, fisheye_host.p95_ms, p_ok ? 1 : 0);
}

int run(int p_argc, char **p_argv) {
	RecordArgs args;
	if (const std::optional<int> done = parse_arguments(p_argc, p_argv, &args)) {
		return *done;
	}
	args.rig_path = absolute_path(args.rig_path);
	args.out = absolute_path(args.out);
	args.rgbd_uri = absolute_if_file(args.rgbd_uri);
	args.fisheye_id = absolute_if_file(args.fisheye_id);
	Rig rig;
	if (const std::optional<int> failed = load_recording_rig(args, &rig)) {
		return *failed;
	}
	args.use_fisheye = args.use_fisheye && rig.has_fisheye();
	HostLatency host;
	drivers::LiveRig live;
	std::string error = live.start(rig, live_settings(args), [&](drivers::CapturedFrame &&p_frame) {
		const double arrival_s = p_frame.host_time_s + (p_frame.is_rgbd ? rig.rgbd_latency_s : rig.fisheye_latency_s);
		const double ms = (double(drivers::monotonic_clock_ns()) * 1e-9 - arrival_s) * 1e3;
		const std::lock_guard<std::mutex> lock(host.mutex);
		host.ms[p_frame.is_rgbd ? 0 : 1].push_back(ms);
	});
	if (!error.empty()) {
		return usage_error(error);
	}
	const RecordingStatus opened = live.start_recording(args.out, nullptr, args.recording_options);
	if (!opened.ok) {
		std::fprintf(stderr, "roomprobe_record: %s\n", opened.error.c_str());
		return 1;
	}
	std::signal(SIGINT, on_interrupt);
	std::signal(SIGTERM, on_interrupt);
	const bool use_rgbd = args.use_rgbd, use_fisheye = args.use_fisheye;
	std::printf("roomprobe_record: recording %s%s into %s%s\n", use_rgbd ? "RGB-D" : "", use_rgbd && use_fisheye ? " and fisheye" : use_fisheye ? "fisheye" : "",
			args.out.c_str(), args.seconds > 0.0 ? (" for " + std::to_string(args.seconds) + " s").c_str() : " until Ctrl-C");
	show_progress(live, args.seconds);
	live.stop();
	const RecordingStatus closed = live.stop_recording();
	const RecordingQueueStatus status = live.recording_status();
	if (!closed.ok) {
		std::fprintf(stderr, "roomprobe_record: %s\n", closed.error.c_str());
	}
	print_summary(args.out, status, host, closed.ok);
	return closed.ok ? 0 : 1;
}

} // namespace

int main(int p_argc, char **p_argv) {
	return roomprobe::cli::guarded_main("roomprobe_record", [&] { return run(p_argc, p_argv); });
}
