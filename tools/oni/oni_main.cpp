// roomprobe_oni: writes a recording's RGB-D stream as an OpenNI .oni file (recording/oni_writer.h),
// so that it plays through OpenNI2 as if from a depth camera: RigCapture's live source, or
// ./roomprobe record --rgbd FILE.oni, without hardware. Tests make their .oni fixtures with it.
//
// usage: roomprobe_oni --recording DIR --out FILE.oni [--first K] [--frames N]
// An existing FILE.oni is never overwritten.

#include "../common/cli.h"

#include <recording/oni_writer.h>

#include <cstdio>
#include <filesystem>
#include <string>

using namespace roomprobe;

namespace {

// --first and --frames (issue #38): up to an hour of frames at 30 Hz; the recording's own count
// limits what is written.
constexpr long MAX_FRAMES = 100000;

int usage_error(const std::string &p_message) {
	std::fprintf(stderr, "roomprobe_oni: %s\nusage: roomprobe_oni --recording DIR --out FILE.oni [--first K] [--frames N]\n", p_message.c_str());
	return 2;
}

int run(int p_argc, char **p_argv) {
	std::string recording, out;
	long first = 0, frames = 0;
	cli::Arguments args(p_argc, p_argv, 1);
	std::string arg;
	while (args.next(&arg)) {
		if (arg == "--recording") {
			if (!args.value(&recording)) {
				return usage_error("--recording needs a folder");
			}
		} else if (arg == "--out") {
			if (!args.value(&out)) {
				return usage_error("--out needs a file");
			}
		} else if (arg == "--first") {
			long value = 0;
			if (!args.integer_in(1, MAX_FRAMES, &value)) {
				return usage_error("--first needs a frame number in " + cli::range_text(1, MAX_FRAMES) + " (frames count from 0; leave it out to start at 0)");
			}
			first = value;
		} else if (arg == "--frames") {
			if (!args.integer_in(1, MAX_FRAMES, &frames)) {
				return usage_error("--frames needs a number of frames in " + cli::range_text(1, MAX_FRAMES));
			}
		} else {
			return usage_error("unknown argument '" + arg + "'");
		}
	}
	if (recording.empty() || out.empty()) {
		return usage_error("--recording and --out are needed");
	}
	std::error_code ec;
	if (std::filesystem::exists(out, ec)) {
		std::fprintf(stderr, "roomprobe_oni: %s: exists; it is not overwritten (remove it first)\n", out.c_str());
		return 1;
	}
	RecordingReader reader;
	const RecordingStatus opened = reader.open(recording);
	if (!opened.ok) {
		std::fprintf(stderr, "roomprobe_oni: %s\n", opened.error.c_str());
		return 1;
	}
	const std::string error = write_oni_from_recording(reader, out, size_t(first), size_t(frames));
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_oni: %s\n", error.c_str()); // the writer left nothing at --out
		return 1;
	}
	const size_t written = frames > 0 ? std::min(size_t(frames), reader.rgbd_count() - size_t(first)) : reader.rgbd_count() - size_t(first);
	std::printf("summary: out=%s frames=%zu width=%d height=%d\n", out.c_str(), written, reader.get_rig().rgb.width, reader.get_rig().rgb.height);
	return 0;
}

} // namespace

int main(int p_argc, char **p_argv) {
	return roomprobe::cli::guarded_main("roomprobe_oni", [&] { return run(p_argc, p_argv); });
}
