#include "rig_calibration.h"

#include "calibration_views.h"
#include "photometric_calibration.h"

#include <camera/least_squares.h>
#include <camera/omni_camera.h>
#include <camera/pinhole_camera.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/ccalib/omnidir.hpp>
#pragma GCC diagnostic pop

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace roomprobe {

namespace {

constexpr double DEG_PER_RAD = 180.0 / std::numbers::pi;

std::string percent(double p_fraction) {
	return std::to_string(int(std::lround(p_fraction * 100.0))) + " %";
}

glm::dvec3 corner_point(const cv::Point3f &p_corner) {
	return glm::dvec3(p_corner.x, p_corner.y, p_corner.z);
}

// Six parameters of a pose (rotation vector, translation) at p_params[p_at].
Pose pose_at(const std::vector<double> &p_params, size_t p_at) {
	Pose pose;
	pose.rotation = rotation_from_vector(glm::dvec3(p_params[p_at], p_params[p_at + 1], p_params[p_at + 2]));
	pose.translation = glm::dvec3(p_params[p_at + 3], p_params[p_at + 4], p_params[p_at + 5]);
	return pose;
}

void push_pose(std::vector<double> &r_params, const Pose &p_pose) {
	const glm::dvec3 r = rotation_vector(p_pose.rotation);
	r_params.insert(r_params.end(), { r.x, r.y, r.z, p_pose.translation.x, p_pose.translation.y, p_pose.translation.z });
}

Pose pose_from_cv(const cv::Mat &p_rvec, const cv::Mat &p_tvec) {
	cv::Mat r, t;
	p_rvec.convertTo(r, CV_64F);
	p_tvec.convertTo(t, CV_64F);
	Pose pose;
	pose.rotation = rotation_from_vector(glm::dvec3(r.at<double>(0), r.at<double>(1), r.at<double>(2)));
	pose.translation = glm::dvec3(t.at<double>(0), t.at<double>(1), t.at<double>(2));
	return pose;
}

// The camera without its image circle and lens angle: a corner a fit moves across the rim still
// projects, and the rim itself unprojects.
OmniParams without_image_circle(const OmniParams &p_camera) {
	OmniParams c = p_camera;
	c.circle_radius = 0.0;
	c.max_angle_deg = 0.0;
	return c;
}

// The omni camera with its fit parameters at p_params[0..8] (xi, fx, fy, cx, cy, k1, k2, p1, p2),
// without its image circle.
OmniParams omni_from(const OmniParams &p_base, const std::vector<double> &p_params) {
	OmniParams c = without_image_circle(p_base);
	c.xi = p_params[0];
	c.fx = p_params[1];
	c.fy = p_params[2];
	c.cx = p_params[3];
	c.cy = p_params[4];
	c.k1 = p_params[5];
	c.k2 = p_params[6];
	c.p1 = p_params[7];
	c.p2 = p_params[8];
	return c;
}

// Residuals (x, y per corner) of p_view's corners projected through p_camera_from_board.
template <class Project>
bool push_residuals(const BoardView &p_view, const std::vector<cv::Point3f> &p_corners, const Pose &p_camera_from_board, Project p_project,
		std::vector<double> &r_residuals) {
	for (size_t i = 0; i < p_corners.size(); i++) {
		glm::dvec2 pixel;
		if (!p_project(transform_point(p_camera_from_board, corner_point(p_corners[i])), &pixel)) {
			return false;
		}
		r_residuals.push_back(pixel.x - p_view.corners[i].x);
		r_residuals.push_back(pixel.y - p_view.corners[i].y);
	}
	return true;
}

double rms_of(const std::vector<double> &p_residuals, size_t p_begin, size_t p_end) {
	double sum = 0.0;
	for (size_t i = p_begin; i < p_end; i++) {
		sum += p_residuals[i] * p_residuals[i];
	}
	// Per corner: x and y together, as OpenCV's calibration RMS.
	return p_end > p_begin ? std::sqrt(sum / double((p_end - p_begin) / 2)) : 0.0;
}

// The board's pose in a fisheye from its corners: their rays turned so that their mean lies on a
// virtual pinhole's axis (near the rim they are far from the fisheye's), then PnP there.
bool fisheye_board_pose(const BoardSpec &p_board, const OmniParams &p_fisheye, const BoardView &p_view, Pose *r_fisheye_from_board) {
	const OmniParams open = without_image_circle(p_fisheye);
	std::vector<glm::dvec3> rays;
	glm::dvec3 mean(0.0);
	for (const cv::Point2f &corner : p_view.corners) {
		glm::dvec3 ray;
		if (!unproject_omni(open, glm::dvec2(corner.x, corner.y), &ray)) {
			return false;
		}
		rays.push_back(glm::normalize(ray));
		mean += rays.back();
	}
	const glm::dvec3 axis = glm::normalize(mean);
	const glm::dvec3 helper = std::abs(axis.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
	const glm::dvec3 x = glm::normalize(glm::cross(helper, axis));
	const glm::dvec3 y = glm::cross(axis, x);
	std::vector<cv::Point2d> normalised;
	for (const glm::dvec3 &ray : rays) {
		const glm::dvec3 v(glm::dot(ray, x), glm::dot(ray, y), glm::dot(ray, axis));
		if (v.z < 0.2) {
			return false;
		}
		normalised.emplace_back(v.x / v.z, v.y / v.z);
	}
	std::vector<cv::Point3d> object;
	for (const cv::Point3f &p : board_corners(p_board)) {
		object.emplace_back(p.x, p.y, p.z);
	}
	cv::Mat rvec, tvec;
	if (!cv::solvePnP(object, normalised, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false, cv::SOLVEPNP_ITERATIVE)) {
		return false;
	}
	const Pose virtual_from_board = pose_from_cv(rvec, tvec);
	Pose fisheye_from_virtual;
	fisheye_from_virtual.rotation = glm::quat_cast(glm::dmat3(x, y, axis)); // columns: the virtual axes in the fisheye
	*r_fisheye_from_board = compose(fisheye_from_virtual, virtual_from_board);
	return true;
}

} // namespace

std::string check_views(const std::vector<BoardView> &p_views, cv::Size p_image_size, const std::string &p_camera, double p_min_span,
		double p_circle_cx, double p_circle_cy, double p_circle_radius) {
	if (p_views.size() < MIN_INTRINSIC_VIEWS) {
		return p_camera + ": too few views with the whole board found: " + std::to_string(p_views.size()) + ", at least " +
				std::to_string(MIN_INTRINSIC_VIEWS) + " are needed (more, and tilted, give a better fit)";
	}
	if (p_circle_radius > 0.0) {
		double reach = 0.0;
		for (const BoardView &view : p_views) {
			for (const cv::Point2f &c : view.corners) {
				reach = std::max(reach, std::hypot(c.x - p_circle_cx, c.y - p_circle_cy) / p_circle_radius);
			}
		}
		if (reach < p_min_span) {
			return p_camera + ": the board is always near the centre of the image (its corners reach " + percent(reach) +
					" of the image circle's radius, " + percent(p_min_span) + " is needed); take views with the board towards the rim";
		}
		return "";
	}
	float min_x = 1e30f, max_x = -1e30f, min_y = 1e30f, max_y = -1e30f;
	for (const BoardView &view : p_views) {
		for (const cv::Point2f &c : view.corners) {
			min_x = std::min(min_x, c.x);
			max_x = std::max(max_x, c.x);
			min_y = std::min(min_y, c.y);
			max_y = std::max(max_y, c.y);
		}
	}
	const double span_x = (max_x - min_x) / p_image_size.width;
	const double span_y = (max_y - min_y) / p_image_size.height;
	if (span_x < p_min_span || span_y < p_min_span) {
		return p_camera + ": the board is always near the centre of the image (its corners span " + percent(span_x) + " of the width and " +
				percent(span_y) + " of the height, " + percent(p_min_span) + " is needed); take views with the board towards the edges and corners";
	}
	return "";
}

PinholeCalibration calibrate_pinhole(const BoardSpec &p_board, cv::Size p_image_size, const std::vector<BoardView> &p_views) {
	PinholeCalibration result;
	result.error = check_views(p_views, p_image_size, "RGB camera");
	if (!result.error.empty()) {
		return result;
	}
	const std::vector<cv::Point3f> corners = board_corners(p_board);
	std::vector<std::vector<cv::Point3f>> object(p_views.size(), corners);
	std::vector<std::vector<cv::Point2f>> image;
	for (const BoardView &view : p_views) {
		image.push_back(view.corners);
	}
	cv::Mat k, d, std_intrinsics, std_extrinsics, per_view;
	std::vector<cv::Mat> rvecs, tvecs;
	try {
		result.rms_px = cv::calibrateCamera(object, image, p_image_size, k, d, rvecs, tvecs, std_intrinsics, std_extrinsics, per_view, cv::CALIB_FIX_K3,
				cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
	} catch (const cv::Exception &e) {
		result.error = "RGB camera: cv::calibrateCamera failed: " + e.err;
		return result;
	}
	PinholeParams &c = result.camera;
	c.width = p_image_size.width;
	c.height = p_image_size.height;
	c.fx = k.at<double>(0, 0);
	c.fy = k.at<double>(1, 1);
	c.cx = k.at<double>(0, 2);
	c.cy = k.at<double>(1, 2);
	c.k1 = d.at<double>(0);
	c.k2 = d.at<double>(1);
	c.p1 = d.at<double>(2);
	c.p2 = d.at<double>(3);
	c.k3 = d.total() > 4 ? d.at<double>(4) : 0.0;
	const auto s = [&](int p_i) { return std_intrinsics.total() > size_t(p_i) ? std_intrinsics.at<double>(p_i) : 0.0; };
	result.std_dev = { 0, 0, s(0), s(1), s(2), s(3), s(4), s(5), s(6), s(7), s(8) };
	for (size_t v = 0; v < p_views.size(); v++) {
		result.camera_from_board.push_back(pose_from_cv(rvecs[v], tvecs[v]));
	}
	if (!std::isfinite(result.rms_px) || !(c.fx > 0.0) || !(c.fy > 0.0)) {
		result.error = "RGB camera: the fit did not converge (RMS " + std::to_string(result.rms_px) + " px)";
	}
	return result;
}

void keep_brightest(cv::Mat &r_brightest, const cv::Mat &p_gray) {
	if (r_brightest.empty()) {
		r_brightest = p_gray.clone();
	} else {
		cv::max(r_brightest, p_gray, r_brightest);
	}
}

ImageCircle lens_circle(const OmniParams &p_lens) {
	if (p_lens.circle_radius > 0.0) {
		return { p_lens.circle_cx, p_lens.circle_cy, p_lens.circle_radius };
	}
	return { p_lens.cx, p_lens.cy, 0.5 * std::min(p_lens.width, p_lens.height) };
}

ImageCircle find_image_circle(const cv::Mat &p_brightest) {
	ImageCircle circle;
	if (p_brightest.empty()) {
		return circle;
	}
	cv::Mat inside;
	cv::threshold(p_brightest, inside, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
	std::vector<std::vector<cv::Point>> contours;
	cv::findContours(inside, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
	const auto largest = std::max_element(contours.begin(), contours.end(),
			[](const auto &p_a, const auto &p_b) { return cv::contourArea(p_a) < cv::contourArea(p_b); });
	if (largest == contours.end() || cv::contourArea(*largest) > 0.97 * double(p_brightest.total())) {
		circle.cx = (p_brightest.cols - 1) * 0.5; // the lens fills the image: no circle
		circle.cy = (p_brightest.rows - 1) * 0.5;
		return circle;
	}
	// The rim's points that do not touch the image's border, fitted by a circle (least squares:
	// x^2 + y^2 + D x + E y + F = 0).
	cv::Mat a(0, 3, CV_64F), b(0, 1, CV_64F);
	for (const cv::Point &p : *largest) {
		if (p.x <= 0 || p.y <= 0 || p.x >= p_brightest.cols - 1 || p.y >= p_brightest.rows - 1) {
			continue;
		}
		const double row[3] = { double(p.x), double(p.y), 1.0 };
		a.push_back(cv::Mat(1, 3, CV_64F, const_cast<double *>(row)).clone());
		b.push_back(-(double(p.x) * p.x + double(p.y) * p.y));
	}
	cv::Mat solution;
	if (a.rows < 3 || !cv::solve(a, b, solution, cv::DECOMP_SVD)) {
		return circle;
	}
	const double d = solution.at<double>(0), e = solution.at<double>(1), f = solution.at<double>(2);
	circle.cx = -d / 2.0;
	circle.cy = -e / 2.0;
	// The contour runs along the outermost bright pixels' centres: half a pixel inside the edge.
	circle.radius = std::sqrt(std::max(0.0, circle.cx * circle.cx + circle.cy * circle.cy - f)) + 0.5;
	return circle;
}

double omni_max_angle_deg(const OmniParams &p_camera) {
	const OmniParams open = without_image_circle(p_camera);
	double widest = 0.0;
	const auto consider = [&](glm::dvec2 p_pixel) {
		glm::dvec3 ray;
		if (unproject_omni(open, p_pixel, &ray)) {
			widest = std::max(widest, std::acos(std::clamp(glm::normalize(ray).z, -1.0, 1.0)) * DEG_PER_RAD);
		}
	};
	if (p_camera.circle_radius > 0.0) {
		for (int i = 0; i < 720; i++) {
			const double a = i * std::numbers::pi / 360.0;
			consider({ p_camera.circle_cx + p_camera.circle_radius * std::cos(a), p_camera.circle_cy + p_camera.circle_radius * std::sin(a) });
		}
	} else {
		for (int x = 0; x < p_camera.width; x++) {
			consider({ double(x), 0.0 });
			consider({ double(x), double(p_camera.height - 1) });
		}
		for (int y = 0; y < p_camera.height; y++) {
			consider({ 0.0, double(y) });
			consider({ double(p_camera.width - 1), double(y) });
		}
	}
	return widest;
}

OmniCalibration calibrate_omni(const BoardSpec &p_board, cv::Size p_image_size, const std::vector<BoardView> &p_views, const ImageCircle &p_circle) {
	OmniCalibration result;
	result.error = check_views(p_views, p_image_size, "fisheye", 0.5, p_circle.cx, p_circle.cy,
			p_circle.radius > 0.0 ? p_circle.radius : 0.5 * std::hypot(p_image_size.width, p_image_size.height));
	if (!result.error.empty()) {
		return result;
	}
	const std::vector<cv::Point3f> corners = board_corners(p_board);
	std::vector<cv::Mat> object, image;
	for (const BoardView &view : p_views) {
		cv::Mat o(1, int(corners.size()), CV_64FC3), i(1, int(corners.size()), CV_64FC2);
		for (size_t k = 0; k < corners.size(); k++) {
			o.at<cv::Vec3d>(0, int(k)) = cv::Vec3d(corners[k].x, corners[k].y, corners[k].z);
			i.at<cv::Vec2d>(0, int(k)) = cv::Vec2d(view.corners[k].x, view.corners[k].y);
		}
		object.push_back(o);
		image.push_back(i);
	}
	cv::Mat k, xi, d, idx;
	std::vector<cv::Mat> rvecs, tvecs;
	try {
		cv::omnidir::calibrate(object, image, p_image_size, k, xi, d, rvecs, tvecs, cv::omnidir::CALIB_FIX_SKEW,
				cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 300, 1e-10), idx);
	} catch (const cv::Exception &e) {
		result.error = "fisheye: cv::omnidir::calibrate failed: " + e.err;
		return result;
	}
	std::vector<int> used;
	if (!idx.empty()) {
		cv::Mat idx_int;
		idx.convertTo(idx_int, CV_32S);
		used.assign(idx_int.begin<int>(), idx_int.end<int>());
	}
	result.views_used = used.size();
	if (used.size() < MIN_INTRINSIC_VIEWS || rvecs.size() != used.size()) {
		result.error = "fisheye: cv::omnidir::calibrate could start from only " + std::to_string(used.size()) + " of " +
				std::to_string(p_views.size()) + " views; " + std::to_string(MIN_INTRINSIC_VIEWS) + " are needed";
		return result;
	}
	OmniParams base;
	base.width = p_image_size.width;
	base.height = p_image_size.height;
	std::vector<double> params = { xi.at<double>(0), k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2), k.at<double>(1, 2), d.at<double>(0),
		d.at<double>(1), d.at<double>(2), d.at<double>(3) };
	for (size_t v = 0; v < used.size(); v++) {
		push_pose(params, pose_from_cv(rvecs[v], tvecs[v]));
	}
	// The same cost in the one projection of the unified model (camera/omni_camera.h): its RMS, and
	// the standard deviations from its Jacobian.
	const ResidualFunction residuals = [&](const std::vector<double> &p_params, std::vector<double> &r_residuals) {
		r_residuals.clear();
		const OmniParams camera = omni_from(base, p_params);
		const auto project = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) { return project_omni(camera, p_point, r_pixel); };
		for (size_t v = 0; v < used.size(); v++) {
			if (!push_residuals(p_views[size_t(used[v])], corners, pose_at(p_params, 9 + 6 * v), project, r_residuals)) {
				return false;
			}
		}
		return true;
	};
	std::vector<double> at_minimum;
	if (!residuals(params, at_minimum)) {
		result.error = "fisheye: the fitted model cannot project every corner of the views it was fitted to";
		return result;
	}
	result.rms_px = rms_of(at_minimum, 0, at_minimum.size());
	const std::vector<double> std_dev = parameter_std_devs(residuals, params);
	result.camera = omni_from(base, params);
	if (std_dev.size() >= 9) {
		result.std_dev = omni_from(OmniParams(), std_dev);
	}
	result.camera.circle_cx = p_circle.radius > 0.0 ? p_circle.cx : result.camera.cx;
	result.camera.circle_cy = p_circle.radius > 0.0 ? p_circle.cy : result.camera.cy;
	result.camera.circle_radius = p_circle.radius;
	result.camera.max_angle_deg = omni_max_angle_deg(result.camera);
	if (!std::isfinite(result.rms_px) || !(result.camera.fx > 0.0) || !(result.camera.fy > 0.0)) {
		result.error = "fisheye: the fit did not converge (RMS " + std::to_string(result.rms_px) + " px)";
	}
	return result;
}

ExtrinsicCalibration calibrate_rgb_from_fisheye(const BoardSpec &p_board, const PinholeParams &p_rgb, const OmniParams &p_fisheye,
		const std::vector<BoardPair> &p_pairs) {
	ExtrinsicCalibration result;
	if (p_pairs.size() < MIN_PAIR_VIEWS) {
		result.error = "rgb_from_fisheye: no view where both cameras see the whole board; hold the board ahead of the rig and raised, "
					   "where the RGB camera and the upward fisheye both see it, and take at least 3 such views";
		return result;
	}
	if ((p_board.inner_x + p_board.inner_y) % 2 == 0) {
		result.error = "rgb_from_fisheye: a board of " + std::to_string(p_board.inner_x) + "x" + std::to_string(p_board.inner_y) +
				" inner corners looks the same turned by half a turn, so the two cameras may number its corners from opposite ends; "
				"use one with an even and an odd number of inner corners (e.g. 9x6)";
		return result;
	}
	const std::vector<cv::Point3f> corners = board_corners(p_board);
	const cv::Mat k = (cv::Mat_<double>(3, 3) << p_rgb.fx, 0.0, p_rgb.cx, 0.0, p_rgb.fy, p_rgb.cy, 0.0, 0.0, 1.0);
	const cv::Mat d = (cv::Mat_<double>(1, 5) << p_rgb.k1, p_rgb.k2, p_rgb.p1, p_rgb.p2, p_rgb.k3);
	// Start: each pair's board pose in the RGB camera by PnP; rgb_from_fisheye from the first pair
	// whose board the fisheye can also place.
	std::vector<double> params(6, 0.0);
	bool started = false;
	for (const BoardPair &pair : p_pairs) {
		cv::Mat rvec, tvec;
		if (!cv::solvePnP(corners, pair.rgb.corners, k, d, rvec, tvec)) {
			result.error = "rgb_from_fisheye: " + pair.rgb.name + ": no board pose (cv::solvePnP failed)";
			return result;
		}
		const Pose rgb_from_board = pose_from_cv(rvec, tvec);
		push_pose(params, rgb_from_board);
		Pose fisheye_from_board;
		if (!started && fisheye_board_pose(p_board, p_fisheye, pair.fisheye, &fisheye_from_board)) {
			const Pose start = compose(rgb_from_board, inverse(fisheye_from_board));
			std::vector<double> first;
			push_pose(first, start);
			std::copy(first.begin(), first.end(), params.begin());
			started = true;
		}
	}
	if (!started) {
		result.error = "rgb_from_fisheye: no pair's board could be placed in the fisheye (its corners' rays); check the fisheye's calibration";
		return result;
	}
	const size_t rgb_count = p_pairs.size() * corners.size() * 2;
	const auto project_rgb = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) { return project_pinhole(p_rgb, p_point, r_pixel); };
	const OmniParams open = without_image_circle(p_fisheye);
	const auto project_fisheye = [&](const glm::dvec3 &p_point, glm::dvec2 *r_pixel) { return project_omni(open, p_point, r_pixel); };
	// Residuals: every pair's RGB corners, then every pair's fisheye corners, in pixels.
	const ResidualFunction residuals = [&](const std::vector<double> &p_params, std::vector<double> &r_residuals) {
		r_residuals.clear();
		const Pose fisheye_from_rgb = inverse(pose_at(p_params, 0));
		for (size_t i = 0; i < p_pairs.size(); i++) {
			if (!push_residuals(p_pairs[i].rgb, corners, pose_at(p_params, 6 + 6 * i), project_rgb, r_residuals)) {
				return false;
			}
		}
		for (size_t i = 0; i < p_pairs.size(); i++) {
			if (!push_residuals(p_pairs[i].fisheye, corners, compose(fisheye_from_rgb, pose_at(p_params, 6 + 6 * i)), project_fisheye, r_residuals)) {
				return false;
			}
		}
		return true;
	};
	const LeastSquaresResult fit = minimize_least_squares(residuals, params);
	std::vector<double> at_minimum;
	if (!fit.ok || !residuals(params, at_minimum)) {
		result.error = "rgb_from_fisheye: the fit could not project the boards from its start (are the pairs' images of one moment?)";
		return result;
	}
	result.rgb_from_fisheye = pose_at(params, 0);
	result.rgb_rms_px = rms_of(at_minimum, 0, rgb_count);
	result.fisheye_rms_px = rms_of(at_minimum, rgb_count, at_minimum.size());
	for (size_t i = 0; i < p_pairs.size(); i++) {
		result.rgb_from_board.push_back(pose_at(params, 6 + 6 * i));
	}
	const std::vector<double> std_dev = parameter_std_devs(residuals, params);
	if (std_dev.size() >= 6) {
		result.rotation_std_deg = glm::dvec3(std_dev[0], std_dev[1], std_dev[2]) * DEG_PER_RAD;
		result.translation_std_m = glm::dvec3(std_dev[3], std_dev[4], std_dev[5]);
	}
	return result;
}

DepthAgreement fit_depth_to_boards(const PinholeParams &p_rgb, const std::vector<BoardPair> &p_pairs, const std::vector<Pose> &p_rgb_from_board) {
	DepthAgreement result;
	// (board depth, measured depth) at every other pixel inside each pair's board.
	std::vector<std::pair<double, double>> samples;
	for (size_t i = 0; i < p_pairs.size() && i < p_rgb_from_board.size(); i++) {
		const cv::Mat &depth = p_pairs[i].depth_m;
		if (depth.empty() || depth.type() != CV_32FC1) {
			continue;
		}
		// Inside the inner corners' hull by 2 px: clear of the depth's discontinuity at the board's edge.
		std::vector<cv::Point2f> hull;
		cv::convexHull(p_pairs[i].rgb.corners, hull);
		const cv::Rect box = cv::boundingRect(hull) & cv::Rect(0, 0, depth.cols, depth.rows);
		const glm::dvec3 normal = p_rgb_from_board[i].rotation * glm::dvec3(0.0, 0.0, 1.0);
		const double plane_d = glm::dot(normal, p_rgb_from_board[i].translation);
		for (int y = box.y; y < box.y + box.height; y += 2) {
			for (int x = box.x; x < box.x + box.width; x += 2) {
				if (cv::pointPolygonTest(hull, cv::Point2f(float(x), float(y)), true) < 2.0) {
					continue;
				}
				const float measured = depth.at<float>(y, x);
				if (!std::isfinite(measured) || measured <= 0.0f) {
					continue;
				}
				const glm::dvec3 ray = unproject_pinhole(p_rgb, glm::dvec2(x, y)); // z = 1
				const double along = glm::dot(normal, ray);
				if (std::abs(along) < 1e-6) {
					continue;
				}
				samples.emplace_back(plane_d / along, measured); // the ray's z is 1: the board's depth
			}
		}
	}
	result.samples = samples.size();
	if (samples.size() < 100) {
		result.error = "depth: fewer than 100 depth readings on the boards of the pairs (" + std::to_string(samples.size()) +
				"); record depth with the pair views (pairs/NNN_depth.png)";
		return result;
	}
	// measured = scale * board + offset, by least squares.
	const double n = double(samples.size());
	double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
	for (const auto &[board_z, measured] : samples) {
		sx += board_z;
		sy += measured;
		sxx += board_z * board_z;
		sxy += board_z * measured;
	}
	const double denominator = n * sxx - sx * sx;
	if (std::abs(denominator) < 1e-12 * n * n) {
		result.error = "depth: the boards are all at one depth, so a scale cannot be told from an offset; take pairs at different distances";
		return result;
	}
	result.scale = (n * sxy - sx * sy) / denominator;
	result.offset_m = (sy - result.scale * sx) / n;
	double residual = 0.0, raw = 0.0;
	for (const auto &[board_z, measured] : samples) {
		const double e = measured - (result.scale * board_z + result.offset_m);
		residual += e * e;
		raw += (measured - board_z) * (measured - board_z);
	}
	result.residual_rms_m = std::sqrt(residual / n);
	result.raw_rms_m = std::sqrt(raw / n);
	return result;
}

RigCalibration calibrate_rig(const CalibrationViews &p_views, const RigCalibrationOptions &p_options) {
	RigCalibration result;
	RigCalibrationReport &report = result.report;
	Rig &rig = result.rig;
	report.board = board_text(p_views.board); // as the user gave it (issue #38: "%g mm" rounded and converted it)
	const PinholeCalibration rgb = calibrate_pinhole(p_views.board, p_views.rgb_size, p_views.rgb);
	if (!rgb.error.empty()) {
		result.error = rgb.error;
		return result;
	}
	rig.rgb = rgb.camera;
	rig.depth_scale_m = p_options.depth_scale_m;
	report.rgb_views = p_views.rgb.size();
	report.rgb_rms_px = rgb.rms_px;
	report.rgb_std = rgb.std_dev;
	if (p_views.fisheye.empty() && p_views.pairs.empty() && !p_options.ocamcalib) {
		result.notes.push_back("no fisheye views: a rig of the RGB-D camera alone");
		return result;
	}
	if (p_options.ocamcalib) {
		OmniFitOptions fit_options;
		fit_options.circle_cx = p_views.fisheye_circle.radius > 0.0 ? p_views.fisheye_circle.cx : -1.0;
		fit_options.circle_cy = p_views.fisheye_circle.radius > 0.0 ? p_views.fisheye_circle.cy : -1.0;
		fit_options.circle_radius = p_views.fisheye_circle.radius;
		const OmniFitResult fit = fit_omni_to_scaramuzza(*p_options.ocamcalib, fit_options);
		if (!fit.ok) {
			result.error = "fisheye: " + p_options.ocamcalib_name + ": " + fit.error;
			return result;
		}
		rig.fisheye = fit.params;
		report.fisheye_method = "unified model fitted to OCamCalib's " + p_options.ocamcalib_name;
		report.fisheye_rms_px = fit.rms_px;
		report.fisheye_views = 0;
		result.notes.push_back("fisheye imported from " + p_options.ocamcalib_name + ": its RMS is the unified model against OCamCalib's rays, and no "
																					   "standard deviations are known");
	} else {
		const OmniCalibration fisheye = calibrate_omni(p_views.board, p_views.fisheye_size, p_views.fisheye, p_views.fisheye_circle);
		if (!fisheye.error.empty()) {
			result.error = fisheye.error;
			return result;
		}
		rig.fisheye = fisheye.camera;
		report.fisheye_method = "cv::omnidir::calibrate";
		report.fisheye_views = fisheye.views_used;
		report.fisheye_rms_px = fisheye.rms_px;
		report.fisheye_std = fisheye.std_dev;
	}
	const ExtrinsicCalibration extrinsic = calibrate_rgb_from_fisheye(p_views.board, rig.rgb, rig.fisheye, p_views.pairs);
	if (!extrinsic.error.empty()) {
		result.error = extrinsic.error;
		return result;
	}
	rig.rgb_from_fisheye = extrinsic.rgb_from_fisheye;
	report.pair_views = p_views.pairs.size();
	report.pair_rgb_rms_px = extrinsic.rgb_rms_px;
	report.pair_fisheye_rms_px = extrinsic.fisheye_rms_px;
	report.rgb_from_fisheye_translation_std_m = extrinsic.translation_std_m;
	report.rgb_from_fisheye_rotation_std_deg = extrinsic.rotation_std_deg;
	rig.fisheye_time_offset_s = 0.0;
	report.clock_offset = "not estimated: fisheye_time_offset_s is 0 (right for a live rig on one host clock; set it by hand for recordings from two clocks)";
	result.notes.push_back(report.clock_offset);
	const DepthAgreement depth = fit_depth_to_boards(rig.rgb, p_views.pairs, extrinsic.rgb_from_board);
	if (depth.error.empty()) {
		report.depth_checked = true;
		report.depth_scale = depth.scale;
		report.depth_offset_m = depth.offset_m;
		report.depth_residual_rms_m = depth.residual_rms_m;
		report.depth_raw_rms_m = depth.raw_rms_m;
		report.depth_samples = depth.samples;
	} else {
		result.notes.push_back(depth.error);
	}
	const PhotometricViews photometric_views = load_photometric_views(p_views.folder, p_views.fisheye_size);
	const PhotometricCalibration photometric = calibrate_photometry(photometric_views, p_views.board, p_views.pairs, rig.fisheye);
	if (photometric.error.empty()) {
		rig.photometry = photometric.photometry;
		report.photometry = photometric.method;
		report.response_fit_rms = photometric.response_rms_ln;
		report.vignetting_fit_rms = photometric.vignetting_rms;
		report.colour_fit_rms = photometric.colour_rms;
	} else if (photometric_views.present) {
		// The user took photometric views: a failed fit is an error, not a rig without photometry.
		result.error = "photometric calibration: " + photometric.error;
		return result;
	} else {
		report.photometry = "not calibrated: no photometric.yaml";
		result.notes.push_back(photometric.error);
	}
	const std::string problem = check_rig(rig);
	if (!problem.empty()) {
		result.error = "the calibrated rig is not usable: " + problem;
	}
	return result;
}

} // namespace roomprobe
