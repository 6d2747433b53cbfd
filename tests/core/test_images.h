#pragma once
// Comparing images in the core tests.

#include <io/opencv.h>

#include <cstring>

// Whether two images are the same: size, type and every value. In float images (one channel: depth in metres)
// NaN means no reading and must be in the same pixels on both sides; cv::norm alone would let a
// NaN pass for any value.
inline bool same_pixels(const cv::Mat &p_a, const cv::Mat &p_b) {
	if (p_a.size() != p_b.size() || p_a.type() != p_b.type()) {
		return false;
	}
	if (p_a.depth() != CV_32F) {
		return cv::norm(p_a, p_b, cv::NORM_INF) == 0.0;
	}
	const cv::Mat a_nan = p_a != p_a;
	const cv::Mat b_nan = p_b != p_b;
	if (cv::countNonZero(a_nan != b_nan) > 0) { // depth is one channel
		return false;
	}
	cv::Mat a = p_a.clone(), b = p_b.clone();
	a.setTo(0.0f, a_nan);
	b.setTo(0.0f, b_nan);
	return cv::norm(a, b, cv::NORM_INF) == 0.0;
}

// Whether two images hold the same bits in every sample (NaN payloads and infinities included):
// what a lossless codec must give back.
inline bool same_samples(const cv::Mat &p_a, const cv::Mat &p_b) {
	if (p_a.type() != p_b.type() || p_a.size() != p_b.size()) {
		return false;
	}
	for (int y = 0; y < p_a.rows; y++) {
		if (std::memcmp(p_a.ptr(y), p_b.ptr(y), size_t(p_a.cols) * p_a.elemSize()) != 0) {
			return false;
		}
	}
	return true;
}
