#include "checkerboard.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace roomprobe {

std::string board_text(const BoardSpec &p_board) {
	char square[32];
	const std::to_chars_result written = std::to_chars(square, square + sizeof(square), p_board.square_m);
	return std::to_string(p_board.inner_x) + "x" + std::to_string(p_board.inner_y) + " inner corners, " + std::string(square, written.ptr) + " m squares";
}

std::string check_board(const BoardSpec &p_board) {
	const std::string name = "board " + board_text(p_board);
	if (p_board.inner_x < 2 || p_board.inner_y < 2) {
		return name + ": needs at least 2x2 inner corners";
	}
	if (p_board.inner_x > BOARD_MAX_INNER_CORNERS || p_board.inner_y > BOARD_MAX_INNER_CORNERS) {
		return name + ": at most " + std::to_string(BOARD_MAX_INNER_CORNERS) + " inner corners a side";
	}
	if (p_board.inner_x == p_board.inner_y) {
		return name + ": as many across as down, so the corners' order is ambiguous; use a board with one more square one way (e.g. 9x6)";
	}
	if (!(p_board.square_m > 0.0 && p_board.square_m < 10.0)) {
		return name + ": the square's side must be within 0 and 10 m";
	}
	return "";
}

std::vector<cv::Point3f> board_corners(const BoardSpec &p_board) {
	std::vector<cv::Point3f> corners;
	for (int j = 0; j < p_board.inner_y; j++) {
		for (int i = 0; i < p_board.inner_x; i++) {
			corners.emplace_back(float((i + 1) * p_board.square_m), float((j + 1) * p_board.square_m), 0.0f);
		}
	}
	return corners;
}

namespace {

// Mean grey level in a small window around p_point (bilinear, clamped to the image).
double mean_around(const cv::Mat &p_gray, cv::Point2f p_point, float p_radius) {
	double sum = 0.0;
	int count = 0;
	for (float dy = -p_radius; dy <= p_radius; dy += 1.0f) {
		for (float dx = -p_radius; dx <= p_radius; dx += 1.0f) {
			const int x = std::clamp(int(std::lround(p_point.x + dx)), 0, p_gray.cols - 1);
			const int y = std::clamp(int(std::lround(p_point.y + dy)), 0, p_gray.rows - 1);
			sum += p_gray.at<uchar>(y, x);
			count++;
		}
	}
	return sum / count;
}

} // namespace

BoardDetection detect_board(const cv::Mat &p_image, const BoardSpec &p_board) {
	BoardDetection result;
	if (p_image.empty() || !check_board(p_board).empty()) {
		return result;
	}
	cv::Mat gray;
	if (p_image.channels() == 3) {
		cv::cvtColor(p_image, gray, cv::COLOR_RGB2GRAY);
	} else {
		gray = p_image;
	}
	const cv::Size pattern(p_board.inner_x, p_board.inner_y);
	std::vector<cv::Point2f> corners;
	result.detector = "findChessboardCornersSB";
	if (!cv::findChessboardCornersSB(gray, pattern, corners, cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY)) {
		result.detector = "findChessboardCorners";
		if (!cv::findChessboardCorners(gray, pattern, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
			return result;
		}
	}
	if (int(corners.size()) != p_board.inner_x * p_board.inner_y) {
		return result;
	}
	// The window: a third of the smallest corner spacing, so it never reaches the next corner.
	float spacing = 1e9f;
	for (int j = 0; j < p_board.inner_y; j++) {
		for (int i = 0; i + 1 < p_board.inner_x; i++) {
			const cv::Point2f d = corners[j * p_board.inner_x + i + 1] - corners[j * p_board.inner_x + i];
			spacing = std::min(spacing, std::hypot(d.x, d.y));
		}
	}
	const int window = std::clamp(int(spacing / 3.0f), 1, 5);
	cv::cornerSubPix(gray, corners, cv::Size(window, window), cv::Size(-1, -1),
			cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 100, 1e-3));
	// The detectors may list the corners from the far end (the board turned by 180 degrees): the
	// outside square diagonal to corner 0 must be the black one, its neighbour along x white.
	const cv::Point2f c0 = corners[0];
	const cv::Point2f along_x = corners[1] - c0;
	const cv::Point2f along_y = corners[p_board.inner_x] - c0;
	const float radius = std::max(0.0f, std::min(std::hypot(along_x.x, along_x.y), std::hypot(along_y.x, along_y.y)) * 0.2f);
	const double origin_square = mean_around(gray, c0 - 0.5f * along_x - 0.5f * along_y, radius);
	const double next_square = mean_around(gray, c0 + 0.5f * along_x - 0.5f * along_y, radius);
	if (origin_square > next_square) {
		std::reverse(corners.begin(), corners.end());
	}
	result.corners = std::move(corners);
	result.found = true;
	return result;
}

cv::Mat gray_8bit(const cv::Mat &p_image) {
	cv::Mat eight = p_image;
	if (p_image.depth() != CV_8U) {
		p_image.convertTo(eight, CV_8U, 255.0);
	}
	cv::Mat gray;
	if (eight.channels() == 3) {
		cv::cvtColor(eight, gray, cv::COLOR_RGB2GRAY);
	} else {
		gray = eight;
	}
	return gray;
}

} // namespace roomprobe
