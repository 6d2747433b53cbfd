#include "recording_types.h"

namespace roomprobe {

const char *recording_stream_name(RecordingStream p_stream) {
	return p_stream == RecordingStream::Fisheye ? "fisheye" : "rgbd";
}

std::string to_string(const RecordingIssue &p_issue) {
	std::string text = p_issue.file;
	if (p_issue.line > 0) {
		text += ":" + std::to_string(p_issue.line);
	}
	return text + ": " + p_issue.message;
}

} // namespace roomprobe
