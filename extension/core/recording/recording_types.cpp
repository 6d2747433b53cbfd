#include "recording_types.h"

#include <set>
#include <cmath>

namespace roomprobe {

const char *recording_stream_name(RecordingStream p_stream) {
	return p_stream == RecordingStream::Fisheye ? "fisheye" : "rgbd";
}

cv::Mat depth_metres_from_raw(const cv::Mat &p_raw, double p_scale_m) {
	cv::Mat depth_m(p_raw.rows, p_raw.cols, CV_32FC1);
	const float no_reading = std::numeric_limits<float>::quiet_NaN();
	for (int y = 0; y < p_raw.rows; y++) {
		const uint16_t *in = p_raw.ptr<uint16_t>(y);
		float *out = depth_m.ptr<float>(y);
		for (int x = 0; x < p_raw.cols; x++) {
			// 0 and 65535 are the sensors' "no reading" (65535: saturated or invalid), never a distance.
			out[x] = in[x] == 0 || in[x] == 65535 ? no_reading : float(double(in[x]) * p_scale_m);
		}
	}
	return depth_m;
}

std::string check_fisheye_image(const FisheyeFrame &p_frame, int p_width, int p_height) {
	const cv::Mat &image = p_frame.image;
	const bool hdr_type = image.type() == CV_32FC3;
	if (image.empty() || (!hdr_type && image.type() != CV_8UC1 && image.type() != CV_8UC3)) {
		return image.empty() ? "an empty image" : "a fisheye image must be CV_8UC1, CV_8UC3 (R, G, B) or CV_32FC3 (HDR)";
	}
	if (p_frame.hdr != hdr_type) {
		return std::string("hdr is ") + (p_frame.hdr ? "set" : "not set") + " but the image is " + (hdr_type ? "float" : "8-bit");
	}
	if (image.cols != p_width || image.rows != p_height) {
		return "the image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) + ", the rig's fisheye " +
				std::to_string(p_width) + "x" + std::to_string(p_height);
	}
	if (hdr_type) {
		cv::Mat finite;
		cv::compare(cv::abs(image.reshape(1)), std::numeric_limits<float>::infinity(), finite, cv::CMP_LT); // false for NaN too
		const int bad = int(finite.total()) - cv::countNonZero(finite);
		if (bad > 0) {
			return std::to_string(bad) + " of its " + std::to_string(finite.total()) + " HDR values are NaN or infinite";
		}
	}
	return std::string();
}

std::vector<std::string> issue_lines(const std::vector<RecordingIssue> &p_issues) {
	std::vector<std::string> lines;
	std::set<std::string> seen;
	for (const RecordingIssue &issue : p_issues) {
		std::string line = to_string(issue);
		if (seen.insert(line).second) {
			lines.push_back(std::move(line));
		}
	}
	return lines;
}

std::string to_string(const RecordingIssue &p_issue) {
	std::string text = p_issue.file;
	if (p_issue.line > 0) {
		text += ":" + std::to_string(p_issue.line);
	}
	return text + ": " + p_issue.message;
}

} // namespace roomprobe
