#pragma once
// Radiance .hdr (RGBE) images, read here rather than by OpenCV's imgcodecs: that one module
// brings GDAL, poppler, HDF5 and about 170 more libraries into every tool that reads a panorama.
// The values are cv::imread's, bit for bit: a pixel (r, g, b, e) is r * 2^(e - 136), ..., and 0
// when e is 0 (OpenCV's rgbe.cpp; Radiance itself adds 0.5 to r, g and b, OpenCV does not).
//
// What is read: a "#?RADIANCE" or "#?RGBE" first line; header lines up to an empty line
// (FORMAT=32-bit_rle_rgbe if there is a FORMAT; XYZE is refused); the resolution line in the
// standard orientation, "-Y HEIGHT +X WIDTH" (top row first, left to right; the others are
// refused); then each scanline flat (4 bytes a pixel), in old-style runs (1, 1, 1, count) or in
// new-style runs (2, 2, width / 256, width % 256, then each channel run-length coded).
//
// Every function returns "" or "NAME: what is wrong" (NAME: the path, or "the data"), and never
// throws. Nothing is read out of bounds, and the image is allocated only once every scanline has
// been found in the bytes, within io/image_codec.h's size limits.

#include "opencv.h"

#include <cstdint>
#include <string>

namespace roomprobe {

// The bytes of a whole .hdr file into linear CV_32FC3 in R, G, B order (not OpenCV's B, G, R).
std::string radiance_hdr_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_rgb);
// The same from a file; errors name p_path.
std::string radiance_hdr_read(const std::string &p_path, cv::Mat *r_rgb);

} // namespace roomprobe
