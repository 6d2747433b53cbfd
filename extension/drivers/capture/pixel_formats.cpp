#include "capture/pixel_formats.h"

#include <opencv2/imgproc.hpp>

namespace roomprobe::drivers {

namespace {

// OpenCV names a Bayer pattern by the second row's second and third pixels, so GenICam's RGGB
// (BayerRG) is OpenCV's BG: the names swap pairwise.
int bayer_to_rgb_code(const std::string &p_format) {
	if (p_format == "BayerRG8") {
		return cv::COLOR_BayerBG2RGB;
	}
	if (p_format == "BayerBG8") {
		return cv::COLOR_BayerRG2RGB;
	}
	if (p_format == "BayerGR8") {
		return cv::COLOR_BayerGB2RGB;
	}
	if (p_format == "BayerGB8") {
		return cv::COLOR_BayerGR2RGB;
	}
	return -1;
}

} // namespace

bool is_supported_pixel_format(const std::string &p_format) {
	return p_format == "Mono8" || p_format == "RGB8" || p_format == "RGB8Packed" || p_format == "BGR8" ||
			p_format == "BGR8Packed" || bayer_to_rgb_code(p_format) >= 0;
}

cv::Mat camera_frame_to_image(const CameraFrame &p_frame, std::string *r_error) {
	const auto fail = [&](const std::string &p_why) {
		if (r_error) {
			*r_error = "a " + std::to_string(p_frame.width) + "x" + std::to_string(p_frame.height) + " " + p_frame.pixel_format + " frame: " + p_why;
		}
		return cv::Mat();
	};
	if (!is_supported_pixel_format(p_frame.pixel_format)) {
		return fail("pixel format not supported (Mono8, RGB8, BGR8, BayerRG8, BayerBG8, BayerGR8, BayerGB8 are)");
	}
	const bool colour = p_frame.pixel_format.rfind("RGB8", 0) == 0 || p_frame.pixel_format.rfind("BGR8", 0) == 0;
	const int channels = colour ? 3 : 1;
	if (p_frame.width <= 0 || p_frame.height <= 0 || p_frame.channels != channels ||
			p_frame.pixels.size() != size_t(p_frame.width) * size_t(p_frame.height) * size_t(channels)) {
		return fail("holds " + std::to_string(p_frame.pixels.size()) + " bytes in " + std::to_string(p_frame.channels) +
				" channels, not " + std::to_string(channels) + " channels of that size");
	}
	// A header over the frame's bytes; every branch below copies out of it.
	const cv::Mat raw(p_frame.height, p_frame.width, CV_8UC(channels), const_cast<uint8_t *>(p_frame.pixels.data()));
	cv::Mat image;
	if (p_frame.pixel_format == "Mono8" || p_frame.pixel_format.rfind("RGB8", 0) == 0) {
		image = raw.clone();
	} else if (p_frame.pixel_format.rfind("BGR8", 0) == 0) {
		cv::cvtColor(raw, image, cv::COLOR_BGR2RGB);
	} else {
		if (p_frame.width < 2 || p_frame.height < 2) {
			return fail("a Bayer mosaic needs at least 2x2 pixels");
		}
		cv::cvtColor(raw, image, bayer_to_rgb_code(p_frame.pixel_format));
	}
	if (r_error) {
		r_error->clear();
	}
	return image;
}

} // namespace roomprobe::drivers
