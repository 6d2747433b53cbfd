#pragma once
// A machine-vision frame as the camera sent it (CameraFrame: Mono8, RGB8, BGR8 or an 8-bit Bayer
// mosaic) to the image the fisheye stage takes: CV_8UC1 gray, or CV_8UC3 in R, G, B order with
// the mosaic demosaiced. The one place that knows GenICam's Bayer names.

#include "../device_types.h"

#include <opencv2/core.hpp>

#include <string>

namespace roomprobe::drivers {

// The image, or empty with *r_error saying which format or size is wrong. The Bayer name gives
// the colours of the top-left 2x2 block read row by row (GenICam's convention: "BayerRG8" starts
// with a red pixel, then green; the next row green, then blue).
cv::Mat camera_frame_to_image(const CameraFrame &p_frame, std::string *r_error);

// Whether camera_frame_to_image takes this GenICam pixel format.
bool is_supported_pixel_format(const std::string &p_format);

} // namespace roomprobe::drivers
