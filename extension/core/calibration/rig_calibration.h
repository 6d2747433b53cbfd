#pragma once
// Calibrating the rig from checkerboard views (paper §3.2, in one place instead of MATLAB,
// OCamCalib and a separate Levenberg-Marquardt): the RGB camera's intrinsics with radial-tangential
// distortion (cv::calibrateCamera), the fisheye's in the unified model (cv::omnidir::calibrate,
// or imported from OCamCalib: camera/scaramuzza.h), rgb_from_fisheye by one Levenberg-Marquardt
// over the views both cameras took at once, and the depth against the board's plane.
//
// Every fit gives its RMS reprojection error and one standard deviation per parameter (from the
// Jacobian at the minimum: camera/least_squares.h), and degenerate input is refused with the
// reason. The projections are the camera models' own (camera/*_camera.h).

#include "checkerboard.h"

#include <camera/camera_params.h>
#include <camera/scaramuzza.h>
#include <math/pose.h>
#include <rig/rig.h>

#include <glm/vec3.hpp>

#include <string>
#include <vector>

namespace roomprobe {

// One image's detected board.
struct BoardView {
	std::string name; // the image, for messages
	std::vector<cv::Point2f> corners; // pixels, in board_corners' order
};

// Fewest views each fit takes.
inline constexpr size_t MIN_INTRINSIC_VIEWS = 4;
inline constexpr size_t MIN_PAIR_VIEWS = 1;

// Empty, or why p_views cannot calibrate p_camera: too few of them, or the board always near the
// middle of the image (its corners must reach p_min_span of the width and height; for a fisheye,
// p_circle_radius > 0, that fraction of the image circle's radius from its centre).
std::string check_views(const std::vector<BoardView> &p_views, cv::Size p_image_size, const std::string &p_camera, double p_min_span = 0.5,
		double p_circle_cx = 0.0, double p_circle_cy = 0.0, double p_circle_radius = 0.0);

struct PinholeCalibration {
	std::string error; // empty: calibrated
	PinholeParams camera;
	PinholeParams std_dev; // one standard deviation of fx .. k3 (width and height unused)
	double rms_px = 0.0;
	std::vector<Pose> camera_from_board; // per view
};

// cv::calibrateCamera with k1, k2, p1, p2 (k3 fixed at 0: a few board views cannot tell it from k1, k2).
PinholeCalibration calibrate_pinhole(const BoardSpec &p_board, cv::Size p_image_size, const std::vector<BoardView> &p_views);

// The fisheye's image circle: the bright disc of p_brightest, the per-pixel maximum of its views
// (CV_8UC1; keep_brightest makes it one view at a time). Radius 0 when the image has no dark
// border (the lens fills it).
struct ImageCircle {
	double cx = 0.0, cy = 0.0, radius = 0.0; // pixels
};
ImageCircle find_image_circle(const cv::Mat &p_brightest);
// A calibrated lens's image circle, or, for a lens without one (radius 0), the image's inscribed
// circle about the principal point: where the photometric and clock fits take their pixels.
ImageCircle lens_circle(const OmniParams &p_lens);
// r_brightest becomes the per-pixel maximum of itself and p_gray (CV_8UC1); empty: p_gray.
void keep_brightest(cv::Mat &r_brightest, const cv::Mat &p_gray);

// The largest angle from the optical axis the camera sees: over its image circle's rim (or the
// image's border when the radius is 0), degrees.
double omni_max_angle_deg(const OmniParams &p_camera);

struct OmniCalibration {
	std::string error;
	OmniParams camera; // with the image circle and max_angle_deg set
	OmniParams std_dev; // one standard deviation of xi, fx, fy, cx, cy, k1, k2, p1, p2
	double rms_px = 0.0;
	size_t views_used = 0; // cv::omnidir::calibrate leaves out views it cannot initialise
};

// cv::omnidir::calibrate (skew fixed at 0), then the image circle and the lens angle.
OmniCalibration calibrate_omni(const BoardSpec &p_board, cv::Size p_image_size, const std::vector<BoardView> &p_views, const ImageCircle &p_circle);

// The board seen by both cameras at once, and the RGB-D camera's depth then (optional).
struct BoardPair {
	BoardView rgb;
	BoardView fisheye;
	cv::Mat depth_m; // CV_32FC1, metres, NaN where there is no reading; empty when not recorded
	cv::Mat rgb_image, fisheye_image; // CV_8UC3 R, G, B: the board's colours (photometric calibration)
};

struct ExtrinsicCalibration {
	std::string error;
	Pose rgb_from_fisheye;
	double rgb_rms_px = 0.0, fisheye_rms_px = 0.0; // of the pairs' corners, at the joint fit
	glm::dvec3 translation_std_m{ 0.0 }; // one standard deviation along x, y, z
	glm::dvec3 rotation_std_deg{ 0.0 }; // of the rotation vector's components
	std::vector<Pose> rgb_from_board; // per pair
};

// One Levenberg-Marquardt over rgb_from_fisheye and every pair's board pose, minimising the
// reprojection errors in both cameras (intrinsics fixed); started from the pairs' own PnP poses.
ExtrinsicCalibration calibrate_rgb_from_fisheye(const BoardSpec &p_board, const PinholeParams &p_rgb, const OmniParams &p_fisheye,
		const std::vector<BoardPair> &p_pairs);

struct DepthAgreement {
	std::string error; // also when no pair has depth
	double scale = 1.0; // measured depth = scale * board depth + offset_m
	double offset_m = 0.0;
	double residual_rms_m = 0.0; // after the scale and offset
	double raw_rms_m = 0.0; // before them: measured - board depth
	size_t samples = 0; // pixels used
};

// The depth images against the board planes of p_rgb_from_board, over the pixels inside each board.
DepthAgreement fit_depth_to_boards(const PinholeParams &p_rgb, const std::vector<BoardPair> &p_pairs, const std::vector<Pose> &p_rgb_from_board);

struct CalibrationViews; // calibration_views.h

struct RigCalibrationOptions {
	double depth_scale_m = 0.001; // written into the rig; the depth PNGs' unit
	// Instead of cv::omnidir::calibrate on the fisheye's views: the unified model fitted to this
	// OCamCalib calibration (the paper's route), in the fisheye views' image size.
	const ScaramuzzaModel *ocamcalib = nullptr;
	std::string ocamcalib_name; // for the report
};

struct RigCalibration {
	std::string error; // the first reason it could not be calibrated
	Rig rig;
	RigCalibrationReport report;
	std::vector<std::string> notes; // what was not done or not checked, for the user
};

// The whole rig from a folder's views: the RGB camera, and when there are fisheye views the
// fisheye and rgb_from_fisheye (which then needs pairs), and the depth when pairs have it. The
// clock offset is not estimated (fisheye_time_offset_s 0; a note says so).
RigCalibration calibrate_rig(const CalibrationViews &p_views, const RigCalibrationOptions &p_options);

} // namespace roomprobe
