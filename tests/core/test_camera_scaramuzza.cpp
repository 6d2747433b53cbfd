// Scaramuzza's model as OCamCalib calibrates it (camera/scaramuzza.h), on a real calibration and
// its real images: /work/shared/data/fisheye-ocamcalib (see ../shared/data/README.md), 16 images
// 748x480 of a checkerboard of 117 mm squares and OCamCalib's calib_results.txt for them.

#include "camera/least_squares.h"
#include "camera/omni_camera.h"
#include "io/opencv.h"
#include "camera/scaramuzza.h"

#include <doctest/doctest.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <numbers>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

const std::string k_data_dir = std::string(ROOMPROBE_SHARED_DATA) + "/fisheye-ocamcalib";
const std::string k_calib_path = k_data_dir + "/calib_results.txt";

// The image circle of these images: in the mean of the 16 images the dark rim begins 286 to 291 px
// from OCamCalib's centre, wherever no object lies across it (measured along 180 directions).
// 285 px keeps the fit and the checks inside the lit disc, about 87 degrees off the axis.
constexpr double k_circle_radius = 285.0;

// The board: 7 x 9 squares of 117 mm, so 6 x 8 inner corners. checkerboard_sizes.txt says
// "5 7", but cv::findChessboardCornersSB finds a full 6 x 8 grid in every image and no 7 x 8,
// 6 x 9 or 7 x 9 one; a 4 x 6 pattern would be only some part of the board.
const cv::Size k_board(6, 8);
constexpr double k_square_m = 0.117;

// Evaluated when the tests register, so that the skip shows in doctest's count.
bool data_missing() {
	const bool missing = !std::filesystem::exists(k_calib_path);
	if (missing) {
		std::fprintf(stderr, "test_camera_scaramuzza: skipping the real-data tests: %s is missing\n", k_calib_path.c_str());
	}
	return missing;
}
const bool k_data_missing = data_missing();

ScaramuzzaModel load_model() {
	const ScaramuzzaLoadResult loaded = load_ocamcalib(k_calib_path);
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	return loaded.model;
}

glm::dvec2 model_centre(const ScaramuzzaModel &p_model) {
	return { p_model.yc, p_model.xc };
}

// Fitted once for the tests that use it.
OmniFitResult fit_model(const ScaramuzzaModel &p_model) {
	static const OmniFitResult fit = [&] {
		OmniFitOptions options;
		options.circle_radius = k_circle_radius;
		return fit_omni_to_scaramuzza(p_model, options);
	}();
	REQUIRE_MESSAGE(fit.ok, fit.error);
	return fit;
}

// findChessboardCornersSB first, then the classic detector for the boards it misses; either way
// refined by cv::cornerSubPix. Without that refinement the sector-based corners fit OCamCalib's
// model worse (1.02 against 0.42 px RMS on Fisheye2_13: its refinement suffers where the squares
// are strongly distorted near the rim); and the classic detector, run first, puts one corner of
// Fisheye2_12 6 px off, next to a cable.
bool detect_corners(const cv::Mat &p_gray, std::vector<cv::Point2f> *r_corners, std::string *r_detector) {
	*r_detector = "findChessboardCornersSB";
	if (!cv::findChessboardCornersSB(p_gray, k_board, *r_corners, cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY)) {
		*r_detector = "findChessboardCorners";
		if (!cv::findChessboardCorners(p_gray, k_board, *r_corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
			return false;
		}
	}
	// A 9x9 window: the smallest squares are some 15 px wide.
	cv::cornerSubPix(p_gray, *r_corners, cv::Size(4, 4), cv::Size(-1, -1), cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 100, 1e-3));
	return true;
}

std::vector<glm::dvec3> board_points() {
	std::vector<glm::dvec3> points;
	for (int row = 0; row < k_board.height; row++) {
		for (int column = 0; column < k_board.width; column++) {
			points.push_back({ column * k_square_m, row * k_square_m, 0.0 });
		}
	}
	return points;
}

glm::dmat3 rodrigues(const double *p_rvec) {
	cv::Matx33d r;
	cv::Rodrigues(cv::Vec3d(p_rvec[0], p_rvec[1], p_rvec[2]), r);
	// glm is column-major.
	return glm::dmat3(r(0, 0), r(1, 0), r(2, 0), r(0, 1), r(1, 1), r(2, 1), r(0, 2), r(1, 2), r(2, 2));
}

// The board's pose (rvec, tvec: camera_from_board) that minimizes the pixel error of p_project
// over the corners, started from the pose of the corners' rays.
template <typename Project>
std::vector<double> fit_board_pose(const std::vector<glm::dvec3> &p_rays, const std::vector<cv::Point2f> &p_corners,
		const Project &p_project, std::vector<double> p_start) {
	const std::vector<glm::dvec3> board = board_points();
	auto residuals = [&](const std::vector<double> &p_params, std::vector<double> &r_residuals) {
		const glm::dmat3 rotation = rodrigues(p_params.data());
		const glm::dvec3 translation(p_params[3], p_params[4], p_params[5]);
		r_residuals.resize(2 * board.size());
		for (size_t i = 0; i < board.size(); i++) {
			glm::dvec2 pixel;
			if (!p_project(rotation * board[i] + translation, &pixel)) {
				return false;
			}
			r_residuals[2 * i] = pixel.x - p_corners[i].x;
			r_residuals[2 * i + 1] = pixel.y - p_corners[i].y;
		}
		return true;
	};
	if (p_start.empty()) {
		// The rays in front, as points of a virtual normalized image plane: a pinhole without
		// distortion, which cv::solvePnP solves. The board lies within some 80 degrees of the axis.
		std::vector<cv::Point3d> object;
		std::vector<cv::Point2d> normalized;
		for (size_t i = 0; i < p_rays.size(); i++) {
			if (p_rays[i].z > 0.15) {
				object.emplace_back(board[i].x, board[i].y, board[i].z);
				normalized.emplace_back(p_rays[i].x / p_rays[i].z, p_rays[i].y / p_rays[i].z);
			}
		}
		REQUIRE(object.size() >= 6);
		cv::Vec3d rvec, tvec;
		REQUIRE(cv::solvePnP(object, normalized, cv::Matx33d::eye(), cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_IPPE));
		p_start = { rvec[0], rvec[1], rvec[2], tvec[0], tvec[1], tvec[2] };
	}
	const LeastSquaresResult result = minimize_least_squares(residuals, p_start);
	REQUIRE(result.ok);
	return p_start;
}

template <typename Project>
double rms_px(const std::vector<double> &p_pose, const std::vector<cv::Point2f> &p_corners, const Project &p_project) {
	const std::vector<glm::dvec3> board = board_points();
	const glm::dmat3 rotation = rodrigues(p_pose.data());
	const glm::dvec3 translation(p_pose[3], p_pose[4], p_pose[5]);
	double sum = 0.0;
	for (size_t i = 0; i < board.size(); i++) {
		glm::dvec2 pixel;
		REQUIRE(p_project(rotation * board[i] + translation, &pixel));
		sum += std::pow(pixel.x - p_corners[i].x, 2) + std::pow(pixel.y - p_corners[i].y, 2);
	}
	return std::sqrt(sum / board.size());
}

std::string temp_path(const std::string &p_name) {
	return (std::filesystem::temp_directory_path() / p_name).string();
}

void write_file(const std::string &p_path, const std::string &p_text) {
	std::ofstream file(p_path);
	file << p_text;
}

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// calib_results.txt's layout, with the real file's numbers; {SS} and the rest are replaced.
std::string calib_text(const std::string &p_ss, const std::string &p_invpol = "3 293.05 151.54 -11.13", const std::string &p_size = "480 748") {
	return "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by cam2world\n\n" + p_ss +
			"\n\n#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used by world2cam\n\n" +
			p_invpol + "\n\n#center: \"row\" and \"column\", starting from 0 (C convention)\n\n241.019976 385.783141\n\n" +
			"#affine parameters \"c\", \"d\", \"e\"\n\n0.998881 -0.042038 0.045079\n\n#image size: \"height\" and \"width\"\n\n" + p_size + "\n";
}

} // namespace

TEST_CASE("scaramuzza: loads OCamCalib's calib_results.txt field by field" * doctest::skip(k_data_missing)) {
	const ScaramuzzaModel model = load_model();
	REQUIRE(model.ss.size() == 5);
	CHECK(model.ss[0] == doctest::Approx(-206.3866));
	CHECK(model.ss[1] == 0.0);
	CHECK(model.ss[4] == doctest::Approx(1.810639e-08));
	REQUIRE(model.invpol.size() == 12);
	CHECK(model.invpol[0] == doctest::Approx(293.052431));
	CHECK(model.invpol[11] == doctest::Approx(0.865190));
	CHECK(model.xc == doctest::Approx(241.019976)); // row
	CHECK(model.yc == doctest::Approx(385.783141)); // column
	CHECK(model.c == doctest::Approx(0.998881));
	CHECK(model.d == doctest::Approx(-0.042038));
	CHECK(model.e == doctest::Approx(0.045079));
	CHECK(model.height == 480);
	CHECK(model.width == 748);

	// The centre's ray is the optical axis, OpenCV's +z; a pixel right of (below) the centre
	// looks right (down), +x (+y).
	const glm::dvec3 axis = unproject_scaramuzza(model, model_centre(model));
	CHECK(axis.z == doctest::Approx(1.0).epsilon(1e-12));
	CHECK(unproject_scaramuzza(model, model_centre(model) + glm::dvec2(100.0, 0.0)).x > 0.0);
	CHECK(unproject_scaramuzza(model, model_centre(model) + glm::dvec2(0.0, 100.0)).y > 0.0);
	glm::dvec2 pixel;
	REQUIRE(project_scaramuzza(model, { 0.0, 0.0, 2.0 }, &pixel));
	CHECK(glm::length(pixel - model_centre(model)) < 1e-12);
	CHECK_FALSE(project_scaramuzza(model, { 0.0, 0.0, -2.0 }, &pixel));
	CHECK_FALSE(project_scaramuzza(model, { 0.0, 0.0, 0.0 }, &pixel));
}

TEST_CASE("scaramuzza: world2cam (invpol) inverts cam2world (ss) over the image circle" * doctest::skip(k_data_missing)) {
	const ScaramuzzaModel model = load_model();
	double worst = 0.0, sum = 0.0, widest_deg = 0.0;
	int count = 0;
	for (int row = 0; row < model.height; row++) {
		for (int column = 0; column < model.width; column++) {
			const glm::dvec2 pixel(column, row);
			if (glm::length(pixel - model_centre(model)) > k_circle_radius) {
				continue;
			}
			const glm::dvec3 ray = unproject_scaramuzza(model, pixel);
			CHECK(std::abs(glm::length(ray) - 1.0) < 1e-12);
			glm::dvec2 back;
			REQUIRE(project_scaramuzza(model, 3.7 * ray, &back));
			const double error = glm::length(back - pixel);
			worst = std::max(worst, error);
			sum += error * error;
			count++;
			widest_deg = std::max(widest_deg, std::acos(ray.z) * 180.0 / std::numbers::pi);
		}
	}
	MESSAGE("cam2world -> world2cam over " << count << " pixels of the image circle (up to " << widest_deg
										   << " degrees off the axis): RMS " << std::sqrt(sum / count) << " px, max " << worst << " px");
	// invpol is only a polynomial fit of ss's inverse: OCamCalib's findinvpoly raises its degree
	// until its largest error over the image is below 0.01 px (here it is ~0.002 px). A wrong
	// axis or affine convention would show as tens of pixels.
	CHECK(worst < 0.01);
}

TEST_CASE("scaramuzza: the unified model fitted to OCamCalib's reprojects its rays to a tenth of a pixel" * doctest::skip(k_data_missing)) {
	const ScaramuzzaModel model = load_model();
	const OmniFitResult fit = fit_model(model);
	const OmniParams &p = fit.params;
	MESSAGE("fitted unified model: xi " << p.xi << ", fx " << p.fx << ", fy " << p.fy << ", cx " << p.cx << ", cy " << p.cy << ", skew "
										<< p.skew << ", k1 " << p.k1 << ", k2 " << p.k2 << ", p1 " << p.p1 << ", p2 " << p.p2
										<< ", roll " << fit.roll_rad << " rad, max angle " << p.max_angle_deg << " deg");
	MESSAGE("reprojection of OCamCalib's rays over " << fit.eval_count << " pixels of the image circle (r " << k_circle_radius
													 << " px; fitted on " << fit.sample_count << "): RMS " << fit.rms_px << " px, max "
													 << fit.max_px << " px");
	// Measured 0.045 px RMS and 0.11 px at worst. A tenth of a pixel RMS (a quarter at worst) is
	// well under the corners' own noise against OCamCalib's model (0.27 px RMS, see the
	// checkerboard test), so running the unified model instead of OCamCalib's adds no error that
	// matters. Without the distortion terms the same fit is ~0.4 px RMS and 1.6 px at worst.
	CHECK(fit.rms_px < 0.1);
	CHECK(fit.max_px < 0.25);
	// The principal point is OCamCalib's centre, and the roll is the rotation in OCamCalib's
	// affine that an upper-triangular K cannot hold: its last row (d, c) in OpenCV's axes.
	CHECK(std::abs(p.cx - model.yc) < 0.05);
	CHECK(std::abs(p.cy - model.xc) < 0.05);
	CHECK(fit.roll_rad == doctest::Approx(std::atan2(model.d, model.c)).epsilon(0.01));
	CHECK(p.max_angle_deg > 85.0);
	CHECK(p.max_angle_deg < 90.0);
	CHECK(p.circle_radius == k_circle_radius);
	CHECK(p.width == 748);
	CHECK(p.height == 480);

	// And through the run-time API, with its circle: every pixel of the circle unprojects to
	// OCamCalib's ray (rotated into the fitted frame) within the fit's error.
	double worst_rad = 0.0;
	for (int row = 0; row < model.height; row += 3) {
		for (int column = 0; column < model.width; column += 3) {
			const glm::dvec2 pixel(column, row);
			glm::dvec3 ray;
			const bool ok = unproject_omni(p, pixel, &ray);
			CHECK(ok == (glm::length(pixel - model_centre(model)) <= k_circle_radius));
			if (ok) {
				worst_rad = std::max(worst_rad, std::acos(std::min(1.0, glm::dot(ray, fit.omni_from_scaramuzza * unproject_scaramuzza(model, pixel)))));
			}
		}
	}
	MESSAGE("largest angle between unproject_omni's and OCamCalib's rays: " << worst_rad << " rad");
	CHECK(worst_rad < 0.25 / 200.0); // 0.25 px at the ~200 px per radian near the rim
}

TEST_CASE("scaramuzza: the real checkerboards reproject through OCamCalib's model and the fitted one" * doctest::skip(k_data_missing)) {
	const ScaramuzzaModel model = load_model();
	const OmniFitResult fit = fit_model(model);
	OmniParams omni = fit.params;
	omni.circle_radius = 0.0; // a few corners lie on the lit disc's edge, beyond the conservative circle
	omni.max_angle_deg = 0.0;
	auto project_ocam = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) { return project_scaramuzza(model, p_point, r_pixel); };
	auto project_unified = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) {
		return project_omni(omni, fit.omni_from_scaramuzza * p_point, r_pixel);
	};
	// What forgetting omni_from_scaramuzza (the 2.4-degree roll) would cost.
	auto project_unified_unrotated = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) { return project_omni(omni, p_point, r_pixel); };

	// The detectors take half a second an image: run them side by side, assert afterwards.
	struct Detection {
		cv::Mat gray;
		bool found = false;
		std::vector<cv::Point2f> corners;
		std::string detector;
	};
	std::vector<std::future<Detection>> detections;
	for (int image = 1; image <= 16; image++) {
		detections.push_back(std::async(std::launch::async, [image] {
			Detection detection;
			detection.gray = cv::imread(k_data_dir + "/Fisheye2_" + std::to_string(image) + ".jpg", cv::IMREAD_GRAYSCALE);
			if (!detection.gray.empty()) {
				detection.found = detect_corners(detection.gray, &detection.corners, &detection.detector);
			}
			return detection;
		}));
	}

	int detected = 0;
	double sum_ocam = 0.0, sum_unified = 0.0, sum_unified_own = 0.0, sum_unrotated = 0.0, worst_ocam = 0.0;
	for (int image = 1; image <= 16; image++) {
		const Detection detection = detections[image - 1].get();
		REQUIRE_MESSAGE(!detection.gray.empty(), "cannot read Fisheye2_" << image << ".jpg");
		CHECK(detection.gray.cols == model.width);
		CHECK(detection.gray.rows == model.height);
		if (!detection.found) {
			MESSAGE("Fisheye2_" << image << ": no 6x8 board found");
			continue;
		}
		const std::vector<cv::Point2f> &corners = detection.corners;
		const std::string &detector = detection.detector;
		detected++;
		std::vector<glm::dvec3> rays;
		for (const cv::Point2f &corner : corners) {
			rays.push_back(unproject_scaramuzza(model, { corner.x, corner.y }));
		}
		const std::vector<double> pose = fit_board_pose(rays, corners, project_ocam, {});
		const double ocam = rms_px(pose, corners, project_ocam);
		// The same pose through the unified model, and the unified model's own best pose.
		const double unified = rms_px(pose, corners, project_unified);
		const double unified_own = rms_px(fit_board_pose(rays, corners, project_unified, pose), corners, project_unified);
		MESSAGE("Fisheye2_" << image << ": board 6x8 (" << detector << ") at " << glm::length(glm::dvec3(pose[3], pose[4], pose[5])) << " m, reprojection RMS: OCamCalib "
							<< ocam << " px, unified (same pose) " << unified << " px, unified (own pose) " << unified_own << " px");
		sum_ocam += ocam * ocam;
		sum_unified += unified * unified;
		sum_unified_own += unified_own * unified_own;
		sum_unrotated += std::pow(rms_px(pose, corners, project_unified_unrotated), 2);
		worst_ocam = std::max(worst_ocam, ocam);
	}
	REQUIRE(detected > 0);
	const double overall_ocam = std::sqrt(sum_ocam / detected), overall_unified = std::sqrt(sum_unified / detected),
				 overall_unified_own = std::sqrt(sum_unified_own / detected), overall_unrotated = std::sqrt(sum_unrotated / detected);
	MESSAGE("boards found in " << detected << " of 16 images; overall reprojection RMS: OCamCalib " << overall_ocam << " px (worst image "
							   << worst_ocam << " px), unified (same poses) " << overall_unified << " px, unified (own poses) "
							   << overall_unified_own << " px; unified without its roll " << overall_unrotated << " px");
	// Measured: boards in all 16 images (Fisheye2_1 and Fisheye2_16 are the same file), 0.27 px
	// RMS overall through OCamCalib's model and 0.42 px for the worst image; the unified model adds
	// 0.003 px. The bounds leave room for another OpenCV's corner detector, and still fail for a
	// wrong convention (the affine transposed, the axes swapped: pixels) or a board pose that
	// did not converge. The unified model, being within 0.1 px of OCamCalib's everywhere, may add
	// no more than a few hundredths.
	CHECK(detected >= 15);
	CHECK(overall_ocam < 0.5);
	CHECK(worst_ocam < 0.8);
	CHECK(overall_unified < overall_ocam + 0.03);
	CHECK(overall_unified_own <= overall_unified + 1e-9);
	CHECK(overall_unrotated > 2.0);
}

TEST_CASE("scaramuzza: a malformed calib_results.txt gives an error naming the file, the line and the field") {
	const std::string path = temp_path("roomprobe_test_camera_bad_calib.txt");

	write_file(path, calib_text("5 -2.063866e+02 0.000000e+00 2.165610e-03 -4.495456e-06"));
	ScaramuzzaLoadResult loaded = load_ocamcalib(path);
	CHECK_FALSE(loaded.ok);
	MESSAGE(loaded.error);
	CHECK(contains(loaded.error, path + ":3: ss: "));
	CHECK(contains(loaded.error, "the count says 5 coefficients but the line has 4"));

	write_file(path, calib_text("4 -206.3866 0 0.0021656 -4.495456e-06", "3 293.05 15x.54 -11.13"));
	loaded = load_ocamcalib(path);
	CHECK_FALSE(loaded.ok);
	MESSAGE(loaded.error);
	CHECK(contains(loaded.error, path + ":7: invpol: "));
	CHECK(contains(loaded.error, "'15x.54'"));

	write_file(path, calib_text("four -206.3866 0 0.0021656 -4.495456e-06"));
	loaded = load_ocamcalib(path);
	CHECK_FALSE(loaded.ok);
	CHECK(contains(loaded.error, path + ":3: ss: the count 'four' is not an integer"));

	write_file(path, calib_text("4 -206.3866 0 0.0021656 -4.495456e-06", "3 293.05 151.54 -11.13", "480"));
	loaded = load_ocamcalib(path);
	CHECK_FALSE(loaded.ok);
	MESSAGE(loaded.error);
	CHECK(contains(loaded.error, path + ":19: image size: "));

	// The file cut after the centre.
	const std::string full = calib_text("4 -206.3866 0 0.0021656 -4.495456e-06");
	write_file(path, full.substr(0, full.find("#affine")));
	loaded = load_ocamcalib(path);
	CHECK_FALSE(loaded.ok);
	MESSAGE(loaded.error);
	CHECK(contains(loaded.error, path + ": affine: missing"));

	// And well formed, it loads.
	write_file(path, full);
	loaded = load_ocamcalib(path);
	CHECK_MESSAGE(loaded.ok, loaded.error);
	CHECK(loaded.model.ss.size() == 4);
	std::filesystem::remove(path);

	const std::string missing = temp_path("roomprobe_test_camera_no_such_calib.txt");
	loaded = load_ocamcalib(missing);
	CHECK_FALSE(loaded.ok);
	CHECK(contains(loaded.error, missing + ": no such file"));
	// Issue #38: a device is named for what it is, and never read (/dev/zero has no end).
	loaded = load_ocamcalib("/dev/zero");
	CHECK(contains(loaded.error, "/dev/zero: not a regular file (a character device)"));
}
