#pragma once
// PNG and JPEG, decoded and encoded by libpng and libjpeg directly. OpenCV's imgcodecs would do
// the same, but Debian builds it with GDAL and GDCM: about 200 more libraries that the shipped
// addon would have to carry (docs/addon.md). The conventions are OpenCV's, so the images go
// straight into cv::Mat code: colour in B, G, R(, A) order, 16 bits kept where asked.
//
// Every function returns "" or what is wrong, and never throws.

#include "opencv.h"

#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

// The largest image decoded: a side of 32768 pixels and 2^28 pixels in all. A header that claims
// more is refused before anything is allocated.
inline constexpr int kImageMaxSidePx = 32768;
inline constexpr int64_t kImageMaxPixels = int64_t(1) << 28;

// "" when an image of p_width x p_height is within those limits, else what is wrong ("is 40000x2
// pixels, more than RoomProbe reads ..."), for a message that names the file first.
std::string image_size_problem(int64_t p_width, int64_t p_height);

// As cv::imdecode(IMREAD_UNCHANGED): 8 or 16 bits as stored, gray stays gray (gray with alpha
// becomes B, G, R, A), colour is B, G, R(, A); palettes and 1-, 2- and 4-bit gray are expanded.
std::string png_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image);
// 8-bit gray or B, G, R.
std::string jpeg_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image);
// An 8- or 16-bit image of 1 (gray), 3 (B, G, R) or 4 (B, G, R, A) channels as PNG bytes.
std::string png_encode(const cv::Mat &p_image, std::vector<uint8_t> *r_bytes);

// The whole of a file's bytes. Errors name p_path ("cannot be opened for reading", "read error").
std::string read_file_bytes(const std::string &p_path, std::vector<uint8_t> *r_bytes);

// A PNG or JPEG file, told apart by its first bytes, read as stored or converted to 8 bits.
enum class ImageReadMode {
	Unchanged, // as png_decode / jpeg_decode give it
	Gray8, // 8-bit gray, as cv::imread(IMREAD_GRAYSCALE)
	Bgr8, // 8-bit B, G, R, as cv::imread(IMREAD_COLOR)
};
// Errors name p_path.
std::string image_read(const std::string &p_path, ImageReadMode p_mode, cv::Mat *r_image);
// Writes png_encode's bytes to p_path, replacing it whole or leaving it as it was (io/replace_file.h):
// a folder or a device there is refused. Errors name p_path.
std::string png_write(const std::string &p_path, const cv::Mat &p_image);

} // namespace roomprobe
