// A frame index (rgb.txt, depth.txt, fisheye.txt; recording/recording_io.h read_frame_index):
// every frame it returns has a finite timestamp, later than the one before, and a relative path
// that stays inside the recording folder. Everything else is an issue naming the line.
#include "fuzz_common.h"

#include <recording/recording_io.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "rgb.txt";
	fuzz::write_bytes(path, p_data, p_size);
	std::vector<FrameRef> frames;
	std::vector<RecordingIssue> issues;
	const std::string error = recording_io::read_frame_index(path.string(), &frames, &issues);
	fuzz::require(error.empty(), "an index file that exists reads:", error);
	for (size_t i = 0; i < frames.size(); i++) {
		const FrameRef &frame = frames[i];
		fuzz::require(std::isfinite(frame.timestamp_s), "a frame's timestamp is finite");
		fuzz::require(i == 0 || frame.timestamp_s > frames[i - 1].timestamp_s, "timestamps increase");
		const std::filesystem::path relative = std::filesystem::path(frame.path).lexically_normal();
		fuzz::require(!relative.empty() && relative.is_relative() && *relative.begin() != "..", "a frame path stays inside:", frame.path);
	}
	for (const RecordingIssue &issue : issues) {
		fuzz::require(issue.line > 0 && !issue.message.empty(), "an issue names its line and says what is wrong");
	}
	return 0;
}
