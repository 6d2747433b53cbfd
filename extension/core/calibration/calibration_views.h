#pragma once
// A folder of checkerboard views for calibrating the rig (./roomprobe calibrate; layout in
// calib/README.md, and the synthetic rig writes one: synth/README.md):
//
//   rgb/*.png (or .jpg)        the RGB camera alone
//   fisheye/*.png (or .jpg)    the fisheye alone
//   pairs/NAME_rgb.png         both cameras at one moment; NAME_fisheye.png beside it, and
//   pairs/NAME_depth.png       optionally the RGB-D camera's 16-bit depth then
//   board.yaml                 optional: inner_corners_x, inner_corners_y, square_m (a synthetic
//                              recording's boards.yaml is read as well)
//
// Each image's board is detected (checkerboard.h); the views of a pair count for each camera's
// intrinsics too.
//
// A recording without calibration/ is a recording of the board held before the rig (./roomprobe
// record): its frames are the views. Up to 120 frames of each camera, spread over the recording,
// are searched; up to 30 views per camera are kept (spread), and up to 15 pairs: an RGB-D frame
// and the fisheye frame within 20 ms of it (one clock when recorded live), both with the board.
// Hold the board still a moment at each pose. Its board comes from board.yaml in the recording
// or from the caller.

#include "rig_calibration.h"

#include <functional>
#include <string>
#include <vector>

namespace roomprobe {

struct CalibrationViews {
	std::string error; // the folder or board unusable, naming it
	std::string folder; // where the views are (p_folder, or its calibration/)
	BoardSpec board;
	bool board_from_file = false;
	cv::Size rgb_size, fisheye_size; // 0x0: no image of that camera
	std::vector<BoardView> rgb, fisheye; // every view of that camera where the whole board was found
	std::vector<BoardPair> pairs; // pairs where both found it
	ImageCircle fisheye_circle; // from every fisheye image
	std::vector<std::string> missed; // images where the board was not found (or unreadable), with why
	size_t images = 0;
};

struct CalibrationViewsOptions {
	BoardSpec board; // used when the folder names none
	bool board_given = false; // the caller's board wins over the folder's
	double depth_scale_m = 0.001; // metres per unit of the depth PNGs
	std::function<void(size_t p_done, size_t p_total, const std::string &p_image)> progress;
};

// Reads p_folder (p_folder/calibration when it holds a recording's views; the recording's frames
// when it is a recording without one).
CalibrationViews load_calibration_views(const std::string &p_folder, const CalibrationViewsOptions &p_options);

} // namespace roomprobe
