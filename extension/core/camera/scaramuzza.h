#pragma once
// Scaramuzza's omnidirectional model as calibrated by OCamCalib (paper §3.2: the fisheye is
// calibrated with it; at run time the unified model of camera_params.h stands in for it, fitted
// here by fit_omni_to_scaramuzza).
//
// OCamCalib's own conventions (ocam_functions.cpp, and its calib_results.txt): a pixel is
// (row, column); its 3-D frame has x along the rows (down), y along the columns (right) and
// z = ss(rho) < 0 for the scene in front, i.e. z points back out of the lens. This file's functions
// speak OpenCV's pixels (x = column, y = row) and camera frame (x right, y down, z forward) only:
//   x_opencv = y_ocam, y_opencv = x_ocam, z_opencv = -z_ocam
// a proper rotation (determinant +1: swapping two axes and negating the third).

#include "camera_params.h"

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <string>
#include <vector>

namespace roomprobe {

// The fields of calib_results.txt, with OCamCalib's names.
struct ScaramuzzaModel {
	std::vector<double> ss; // direct polynomial a0, a1, ...: z = sum a_i rho^i (cam2world)
	std::vector<double> invpol; // inverse polynomial b0, b1, ...: rho = sum b_i theta^i (world2cam)
	double xc = 0.0; // centre's row, pixels from 0
	double yc = 0.0; // centre's column, pixels from 0
	double c = 1.0, d = 0.0, e = 0.0; // affine: [row; col] = [c d; e 1] [x; y] + [xc; yc]
	int width = 0; // pixels
	int height = 0; // pixels
};

struct ScaramuzzaLoadResult {
	bool ok = false;
	std::string error; // names the file, the line and the field, e.g. "calib_results.txt:3: ss: ..."
	ScaramuzzaModel model;
};

// Reads OCamCalib's calib_results.txt: lines starting with '#' are comments, blank lines are
// skipped, and the data come in this order, one line each: ss (count, then that many
// coefficients), invpol (likewise), the centre (row, column), the affine c d e, and the image
// height and width. Anything after the image size is ignored, as OCamCalib's reader does.
ScaramuzzaLoadResult load_ocamcalib(const std::string &p_path);

// world2cam through invpol, for a point in OpenCV's camera frame. False for the zero vector, a
// point straight behind the lens, or where invpol gives a negative radius (far outside its fit).
bool project_scaramuzza(const ScaramuzzaModel &p_model, const glm::dvec3 &p_point, glm::dvec2 *r_pixel);
// cam2world through ss: the unit ray of a pixel, in OpenCV's camera frame. Exact by definition of
// the model (invpol is only ss's approximate inverse).
glm::dvec3 unproject_scaramuzza(const ScaramuzzaModel &p_model, const glm::dvec2 &p_pixel);

struct OmniFitOptions {
	// The image circle, pixels (x = column, y = row); a negative centre means OCamCalib's centre.
	// The fit samples pixels inside the image and this circle; radius 0: the whole image.
	double circle_cx = -1.0;
	double circle_cy = -1.0;
	double circle_radius = 0.0;
	double sample_step_px = 6.0; // grid spacing of the fitted pixels (plus the circle's rim)
	double eval_step_px = 1.0; // grid spacing of the pixels the reported errors are measured on
	bool fit_distortion = true; // k1 k2 p1 p2; otherwise only xi, K and the roll
	bool fit_skew = true;
};

struct OmniFitResult {
	bool ok = false;
	std::string error;
	// The unified model, with the image size, circle and max_angle_deg (the largest angle seen on
	// the circle's rim) filled in.
	OmniParams params;
	// OCamCalib's affine holds a small rotation about the optical axis (its roll is a gauge freedom
	// of its calibration, absorbed by the board poses) that OmniParams cannot express, so the fit
	// rotates the frame: ray_omni = omni_from_scaramuzza * ray_scaramuzza, a rotation by roll_rad
	// about z. An extrinsic calibrated in OCamCalib's frame must be composed with it.
	glm::dmat3 omni_from_scaramuzza = glm::dmat3(1.0);
	double roll_rad = 0.0;
	// Reprojection of OCamCalib's rays (cam2world, exact) through the fitted model, over the
	// eval grid in the image circle: pixels.
	double rms_px = 0.0;
	double max_px = 0.0;
	int sample_count = 0; // pixels fitted
	int eval_count = 0; // pixels measured
};

// Fits OmniParams to the OCamCalib model by Levenberg-Marquardt on the pixel error of the rays of
// pixels sampled over the image circle.
OmniFitResult fit_omni_to_scaramuzza(const ScaramuzzaModel &p_model, const OmniFitOptions &p_options = {});

} // namespace roomprobe
