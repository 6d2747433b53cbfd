#pragma once
// Raw frame files: an image's samples as they lie in memory, compressed by zstd (libzstd), behind
// a small header that says what they are. Recordings store their frames so (issue #36): a frame
// decodes about ten times faster than a PNG of it, losslessly. The file is a valid zstd file: the
// header is a zstd skippable frame, which `zstd -d` passes over, so the standard tool unpacks the
// samples (docs/recording-format.md, "Raw frame files", byte by byte).
//
// Samples are stored as given: the recording stores colour as R, G, B (not OpenCV's B, G, R).
// Every function returns "" or what is wrong, and never throws.

#include "opencv.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

// The header's size in bytes: the zstd data starts here.
inline constexpr size_t kRawFrameHeaderBytes = 32;
// The format version written and read.
inline constexpr int kRawFrameVersion = 1;
// The compression level recordings use: zstd's fastest positive level (docs/recording-format.md
// has the measurements); the decoding speed hardly depends on it.
inline constexpr int kRawFrameDefaultLevel = 1;
// The most bytes of samples decoded (besides io/image_codec.h's pixel limits): 1 GiB.
inline constexpr uint64_t kRawFrameMaxBytes = uint64_t(1) << 30;

struct RawFrameHeader {
	int width = 0;
	int height = 0;
	int channels = 0; // 1 to 4
	int depth = 0; // CV_8U, CV_16U, CV_16F or CV_32F
	uint64_t data_bytes = 0; // the zstd data after the header: the whole file is kRawFrameHeaderBytes + this
	int cv_type() const { return CV_MAKETYPE(depth, channels); }
	// width x height x channels x bytes per sample: what the zstd data decompresses to.
	uint64_t sample_bytes() const;
};

// True when p_bytes begin as a raw frame file does (its first 12 bytes; fewer: false).
bool raw_frame_signature(const uint8_t *p_bytes, size_t p_size);
// True when p_bytes begin with one of zstd's magic numbers (a frame's or a skippable frame's): a raw
// frame file, or a zstd file that raw_frame_parse_header says is not one.
bool zstd_magic(const uint8_t *p_bytes, size_t p_size);
// Reads and checks the header from the first kRawFrameHeaderBytes of p_bytes (p_size may be
// smaller: "truncated"): signature, version, sample type, channels, size within the limits.
std::string raw_frame_parse_header(const uint8_t *p_bytes, size_t p_size, RawFrameHeader *r_header);
// A whole file's bytes as the image the header describes (the samples as stored). Refused before
// anything is allocated: a bad header, a file of another length than the header says, zstd data
// whose declared size is not the header's. Then corrupt data and a wrong checksum are errors.
std::string raw_frame_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image);
// An 8-bit, 16-bit, half or float image of 1 to 4 channels as a raw frame file's bytes, at zstd
// level p_level (ZSTD_minCLevel() to ZSTD_maxCLevel(); 1 to 3 are the fast ones).
std::string raw_frame_encode(const cv::Mat &p_image, int p_level, std::vector<uint8_t> *r_bytes);
// "" when zstd has level p_level, else what is wrong.
std::string raw_frame_level_problem(int p_level);
// Writes raw_frame_encode's bytes to p_path, whole or not at all (io/replace_file.h). Errors name p_path.
std::string raw_frame_write(const std::string &p_path, const cv::Mat &p_image, int p_level = kRawFrameDefaultLevel);

} // namespace roomprobe
