#pragma once
// The issues a RecordingReader collected, one per line, for test failure messages.

#include "recording/recording_reader.h"

#include <string>

namespace recording_test {

inline std::string all_issues(const roomprobe::RecordingReader &p_reader) {
	std::string text;
	for (const roomprobe::RecordingIssue &issue : p_reader.get_issues()) {
		text += roomprobe::to_string(issue) + "\n";
	}
	return text;
}

} // namespace recording_test
