#pragma once
// The calibration board (paper §3.2: both cameras are calibrated from checkerboard views): its
// corners in its own frame and their detection in an image, in one order for every camera, so
// that a view the RGB camera and the fisheye take at once names the same corners.
//
// The board frame is the synthetic rig's (synth/synth_sequence.h): inner corner (i, j) at
// ((i + 1) square_m, (j + 1) square_m, 0), i fastest; the square at the origin, outside corner
// (0, 0), is black. A board with as many inner corners across as down is refused: its corners
// could be listed from four ends.

#include <io/opencv.h>

#include <string>
#include <vector>

namespace roomprobe {

struct BoardSpec {
	int inner_x = 9; // inner corners along the board's x (squares - 1)
	int inner_y = 6;
	double square_m = 0.035; // side of one square, metres
};

// The board as the user gave it, for messages: "9x6 inner corners, 0.035 m squares" (the size in
// metres, as --square-m and board.yaml take it, written as the shortest text that reads back as the
// same number: never rounded, nor turned into millimetres).
std::string board_text(const BoardSpec &p_board);

// The most inner corners a side: no printed board has 100 (--board's bound too).
constexpr int BOARD_MAX_INNER_CORNERS = 100;

// Empty, or what is wrong with the board ("board 7x7 inner corners, 0.035 m squares: ...").
std::string check_board(const BoardSpec &p_board);

// The inner corners in the board frame, metres, i fastest.
std::vector<cv::Point3f> board_corners(const BoardSpec &p_board);

struct BoardDetection {
	bool found = false;
	std::vector<cv::Point2f> corners; // pixels, in board_corners' order
	std::string detector; // which detector found them
};

// Finds every inner corner of the board in a CV_8UC1 or CV_8UC3 image: cv::findChessboardCornersSB,
// then the classic detector, refined by cv::cornerSubPix; the order is then fixed so that corner
// 0 is the one next to the black outside square.
BoardDetection detect_board(const cv::Mat &p_image, const BoardSpec &p_board);

// A recording's frame as the detectors and trackers take it: 8-bit grey from R, G, B (or grey),
// an HDR frame (CV_32F, linear) scaled by 255 and clipped.
cv::Mat gray_8bit(const cv::Mat &p_image);

} // namespace roomprobe
