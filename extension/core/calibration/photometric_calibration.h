#pragma once
// The rig's photometric calibration (rig/photometry.h), from views beside the checkerboard views
// (calibration_views.h's folder; calib/README.md):
//
//   photometric.yaml     reference_exposure_us (the fisheye's exposure in the pairs' images),
//                        exposure_sweep: [{image, exposure_us}, ...], flat_field: {image, exposure_us}
//   exposure/*.png       the fisheye, held still, one static scene at several exposures
//   flat_field.png       the fisheye through a diffuser in even light (a uniform radiance)
//
// It fits, in this order:
//   1. the fisheye's response, Debevec-Malik over the sweep (cv::CalibrateDebevec), on the square
//      inside the image circle (the black outside carries no exposure information);
//   2. its vignetting, from the flat field linearised by that response: a radial table over the
//      image circle, 1 at the centre;
//   3. the colour transform: per-channel gains that take the fisheye's linear values to the RGB
//      camera's on the board squares both cameras see in the pairs (a grey board fixes a
//      diagonal transform, not a full 3x3 one).
// The RGB camera is taken as sRGB at a fixed exposure: its linear value is the rig's unit.

#include "rig_calibration.h"

#include <rig/photometry.h>

#include <limits>
#include <string>
#include <vector>

namespace roomprobe {

struct PhotometricViews {
	std::string error; // photometric.yaml or an image it names is unusable, naming it
	bool present = false; // the folder has photometric.yaml
	double reference_exposure_us = std::numeric_limits<double>::quiet_NaN();
	std::vector<cv::Mat> sweep; // CV_8UC3 R, G, B, the fisheye's size
	std::vector<double> sweep_exposure_us;
	cv::Mat flat_field; // CV_8UC3 R, G, B
};

// Reads p_folder/photometric.yaml and its images (p_folder: the views' folder, the one
// load_calibration_views used). present == false without an error when there is no such file.
PhotometricViews load_photometric_views(const std::string &p_folder, cv::Size p_fisheye_size);

struct ResponseFit {
	std::string error;
	std::array<ResponseCurve, 3> response{}; // R, G, B, relative (code 128 at 1)
	double rms_ln = 0.0; // the sweep's residual ln(response) - ln(exposure) - ln(radiance), over the samples used
	size_t samples = 0;
};
// At least 3 exposures spanning at least 4 stops.
ResponseFit fit_response(const std::vector<cv::Mat> &p_sweep, const std::vector<double> &p_exposure_us, const OmniParams &p_fisheye);

struct VignettingFit {
	std::string error;
	std::vector<float> table; // CameraPhotometry::vignetting
	double rms = 0.0; // relative, the flat field's pixels against the table
};
VignettingFit fit_vignetting(const cv::Mat &p_flat_field, const std::array<ResponseCurve, 3> &p_response, const OmniParams &p_fisheye, int p_nodes = 33);

struct ColourFit {
	std::string error;
	glm::dvec3 gains{ 1.0 }; // fisheye linear (response over vignetting) -> the RGB camera's linear
	double rms = 0.0; // relative, over the squares and channels used
	size_t squares = 0;
};
// The pairs need their images (BoardPair::rgb_image, fisheye_image), taken with the fisheye at the
// reference exposure.
ColourFit fit_colour_gains(const BoardSpec &p_board, const std::vector<BoardPair> &p_pairs, const CameraPhotometry &p_fisheye_linear,
		const OmniParams &p_fisheye, const CameraPhotometry &p_rgb);

struct PhotometricCalibration {
	std::string error;
	RigPhotometry photometry;
	std::string method; // for the report
	double response_rms_ln = 0.0, vignetting_rms = 0.0, colour_rms = 0.0;
};
PhotometricCalibration calibrate_photometry(const PhotometricViews &p_views, const BoardSpec &p_board, const std::vector<BoardPair> &p_pairs,
		const OmniParams &p_fisheye);

} // namespace roomprobe
