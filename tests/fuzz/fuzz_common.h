#pragma once
// What the libFuzzer targets share (tests/fuzz/README.md). Each target hands the fuzzer's bytes
// to the public loader a user's file reaches, through a real file: the loaders take paths, and
// the path is what a user gives them. A broken invariant aborts, so libFuzzer keeps the input.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <opencv2/core.hpp>

namespace roomprobe::fuzz {

// The target's own scratch folder (TMPDIR, else /tmp), one per process so that parallel jobs
// (-jobs, -fork) never share files.
inline const std::filesystem::path &scratch() {
	static const std::filesystem::path folder = [] {
		const char *tmp = std::getenv("TMPDIR");
		std::filesystem::path path = std::filesystem::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") /
				("roomprobe-fuzz-" + std::to_string(getpid()));
		std::filesystem::create_directories(path);
		return path;
	}();
	return folder;
}

inline void write_bytes(const std::filesystem::path &p_path, const uint8_t *p_data, size_t p_size) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file.write(reinterpret_cast<const char *>(p_data), std::streamsize(p_size));
}

// An invariant the loaders promise; a broken one is a finding.
inline void require(bool p_holds, const char *p_what, const std::string &p_detail = std::string()) {
	if (!p_holds) {
		std::fprintf(stderr, "roomprobe fuzz: broken invariant: %s %s\n", p_what, p_detail.c_str());
		std::abort();
	}
}

// True when every value of a float image is finite.
inline bool all_finite(const cv::Mat &p_image) {
	return cv::checkRange(p_image, true, nullptr, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max());
}

} // namespace roomprobe::fuzz
