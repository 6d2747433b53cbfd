#include "clock_offset.h"

#include "checkerboard.h"
#include "rig_calibration.h"

#include <camera/omni_camera.h>
#include <camera/pinhole_camera.h>
#include <math/pose.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/video/tracking.hpp>

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

namespace roomprobe {

namespace {

constexpr double DEG = 180.0 / std::numbers::pi;

// Features of p_prev tracked into p_next (forward only, status checked).
void track(const cv::Mat &p_prev, const cv::Mat &p_next, const cv::Mat &p_mask, std::vector<cv::Point2f> *r_from, std::vector<cv::Point2f> *r_to) {
	std::vector<cv::Point2f> corners;
	cv::goodFeaturesToTrack(p_prev, corners, 1000, 0.003, 6.0, p_mask);
	r_from->clear();
	r_to->clear();
	if (corners.size() < 8) {
		return;
	}
	std::vector<cv::Point2f> moved;
	std::vector<uchar> status;
	std::vector<float> error;
	cv::calcOpticalFlowPyrLK(p_prev, p_next, corners, moved, status, error, cv::Size(21, 21), 3);
	for (size_t i = 0; i < corners.size(); i++) {
		if (status[i] && moved[i].x >= 0.0f && moved[i].y >= 0.0f && moved[i].x < p_next.cols && moved[i].y < p_next.rows) {
			r_from->push_back(corners[i]);
			r_to->push_back(moved[i]);
		}
	}
}

glm::dquat quat_from_rvec(const cv::Mat &p_rvec) {
	return rotation_from_vector(glm::dvec3(p_rvec.at<double>(0), p_rvec.at<double>(1), p_rvec.at<double>(2)));
}

glm::dquat quat_from_matrix(const cv::Mat &p_r) {
	cv::Mat rvec;
	cv::Rodrigues(p_r, rvec);
	return quat_from_rvec(rvec);
}

// The RGB-D camera's orientations (world_from_camera, the first frame's = identity) over one
// unbroken run of frames.
struct OrientationRun {
	std::vector<double> times;
	std::vector<glm::dquat> orientations;
};

// cam_next_from_cam_prev of one RGB-D step, from the previous frame's features with depth.
bool rgbd_step(const PinholeParams &p_camera, const cv::Mat &p_prev_gray, const cv::Mat &p_prev_depth, const cv::Mat &p_next_gray, glm::dquat *r_step) {
	cv::Mat mask;
	cv::Mat valid = p_prev_depth == p_prev_depth; // not NaN
	valid.convertTo(mask, CV_8U);
	std::vector<cv::Point2f> from, to;
	track(p_prev_gray, p_next_gray, mask, &from, &to);
	std::vector<cv::Point3f> points;
	std::vector<cv::Point2f> seen;
	for (size_t i = 0; i < from.size(); i++) {
		const float z = p_prev_depth.at<float>(cvRound(from[i].y), cvRound(from[i].x));
		if (!(z > 0.0f)) {
			continue;
		}
		const glm::dvec3 ray = unproject_pinhole(p_camera, glm::dvec2(from[i].x, from[i].y));
		const glm::dvec3 next = unproject_pinhole(p_camera, glm::dvec2(to[i].x, to[i].y));
		points.emplace_back(float(ray.x * z), float(ray.y * z), float(z));
		seen.emplace_back(float(next.x), float(next.y)); // normalised, undistorted
	}
	if (points.size() < 12) {
		return false;
	}
	cv::Mat rvec, tvec;
	std::vector<int> inliers;
	const double threshold = 1.5 / p_camera.fx; // pixels -> normalised
	if (!cv::solvePnPRansac(points, seen, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false, 200, float(threshold), 0.999, inliers, cv::SOLVEPNP_EPNP) ||
			inliers.size() < 10) {
		return false;
	}
	std::vector<cv::Point3f> in_points;
	std::vector<cv::Point2f> in_seen;
	for (int i : inliers) {
		in_points.push_back(points[size_t(i)]);
		in_seen.push_back(seen[size_t(i)]);
	}
	cv::solvePnP(in_points, in_seen, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
	*r_step = quat_from_rvec(rvec);
	return true;
}

// cam_next_from_cam_prev of one fisheye step, from the tracked features' rays.
bool fisheye_step(const OmniParams &p_camera, const cv::Mat &p_prev_gray, const cv::Mat &p_next_gray, const cv::Mat &p_mask, glm::dquat *r_step) {
	std::vector<cv::Point2f> from, to;
	track(p_prev_gray, p_next_gray, p_mask, &from, &to);
	std::vector<cv::Point2f> a, b;
	for (size_t i = 0; i < from.size(); i++) {
		glm::dvec3 ra, rb;
		// Rays within about 81 degrees of the axis: the essential matrix works on a plane.
		if (!unproject_omni(p_camera, glm::dvec2(from[i].x, from[i].y), &ra) || !unproject_omni(p_camera, glm::dvec2(to[i].x, to[i].y), &rb)) {
			continue;
		}
		ra = glm::normalize(ra);
		rb = glm::normalize(rb);
		if (ra.z < 0.15 || rb.z < 0.15) {
			continue;
		}
		a.emplace_back(float(ra.x / ra.z), float(ra.y / ra.z));
		b.emplace_back(float(rb.x / rb.z), float(rb.y / rb.z));
	}
	if (a.size() < 16) {
		return false;
	}
	const double threshold = 1.0 / p_camera.fx;
	cv::Mat inliers;
	const cv::Mat e = cv::findEssentialMat(a, b, cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, 0.999, threshold, 2000, inliers);
	if (e.rows != 3 || e.cols != 3) {
		return false;
	}
	cv::Mat r, t;
	if (cv::recoverPose(e, a, b, cv::Mat::eye(3, 3, CV_64F), r, t, inliers) < 12) {
		return false;
	}
	*r_step = quat_from_matrix(r);
	return true;
}

// The orientation at p_time within a run (slerp); false outside it.
bool orientation_at(const OrientationRun &p_run, double p_time, glm::dquat *r_orientation) {
	const std::vector<double> &t = p_run.times;
	if (t.size() < 2 || p_time < t.front() || p_time > t.back()) {
		return false;
	}
	const size_t i = std::min(size_t(std::upper_bound(t.begin(), t.end(), p_time) - t.begin()), t.size() - 1);
	const double u = (p_time - t[i - 1]) / (t[i] - t[i - 1]);
	*r_orientation = glm::slerp(p_run.orientations[i - 1], p_run.orientations[i], u);
	return true;
}

struct FisheyeStep {
	double t0 = 0.0, t1 = 0.0; // fisheye clock
	glm::dquat rotation; // cam1_from_cam0
};

// The residual vectors (rotation vectors of measured * predicted^-1, radians) of the steps at d.
std::vector<glm::dvec3> residuals(const std::vector<OrientationRun> &p_runs, const std::vector<FisheyeStep> &p_steps, const glm::dquat &p_rgb_from_fisheye,
		double p_offset, const std::vector<uint8_t> &p_use) {
	std::vector<glm::dvec3> out;
	for (size_t k = 0; k < p_steps.size(); k++) {
		if (!p_use[k]) {
			continue;
		}
		const FisheyeStep &s = p_steps[k];
		bool found = false;
		for (const OrientationRun &run : p_runs) {
			glm::dquat o0, o1;
			if (orientation_at(run, s.t0 + p_offset, &o0) && orientation_at(run, s.t1 + p_offset, &o1)) {
				const glm::dquat rgb_step = glm::inverse(o1) * o0; // cam1_from_cam0
				const glm::dquat predicted = glm::inverse(p_rgb_from_fisheye) * rgb_step * p_rgb_from_fisheye;
				out.push_back(rotation_vector(s.rotation * glm::inverse(predicted)));
				found = true;
				break;
			}
		}
		if (!found) {
			out.push_back(glm::dvec3(std::numeric_limits<double>::quiet_NaN()));
		}
	}
	return out;
}

// Mean squared component over the steps every candidate offset can explain.
double cost(const std::vector<glm::dvec3> &p_residuals, size_t *r_count) {
	double sum = 0.0;
	size_t n = 0;
	for (const glm::dvec3 &r : p_residuals) {
		if (std::isfinite(r.x)) {
			sum += glm::dot(r, r);
			n++;
		}
	}
	*r_count = n;
	return n ? sum / double(3 * n) : std::numeric_limits<double>::infinity();
}

// 1. The RGB-D camera's orientations, in runs broken where a step fails. False on a read error
// (r_result->error says it); r_result->rgbd_steps counts the steps.
bool rgbd_orientations(const RecordingReader &p_reader, const Rig &p_rig, const ClockOffsetOptions &p_options, double p_start,
		std::vector<OrientationRun> *r_runs, ClockOffsetEstimate *r_result) {
	std::vector<OrientationRun> &runs = *r_runs;
	cv::Mat prev_gray, prev_depth;
	double prev_time = 0.0;
	for (size_t i = 0; i < p_reader.rgbd_count(); i++) {
		const RgbdFrameResult read = p_reader.read_rgbd(i);
		if (!read.ok) {
			r_result->error = read.error;
			return false;
		}
		if (read.frame.timestamp_s - p_start > p_options.max_seconds) {
			break;
		}
		const cv::Mat gray = gray_8bit(read.frame.rgb);
		glm::dquat step;
		OrientationRun &run = runs.back();
		if (!prev_gray.empty() && rgbd_step(p_rig.rgb, prev_gray, prev_depth, gray, &step)) {
			r_result->rgbd_steps++;
			if (run.times.empty()) {
				run.times.push_back(prev_time);
				run.orientations.push_back(glm::dquat(1.0, 0.0, 0.0, 0.0));
			}
			run.times.push_back(read.frame.timestamp_s);
			run.orientations.push_back(glm::normalize(run.orientations.back() * glm::inverse(step)));
		} else if (!run.times.empty()) {
			runs.emplace_back();
		}
		prev_gray = gray;
		prev_depth = read.frame.depth_m;
		prev_time = read.frame.timestamp_s;
	}
	return true;
}

// 2. The fisheye's steps. False on a read error (r_result->error says it).
bool fisheye_steps(const RecordingReader &p_reader, const Rig &p_rig, const ClockOffsetOptions &p_options, double p_start,
		std::vector<FisheyeStep> *r_steps, ClockOffsetEstimate *r_result) {
	const OmniParams &lens = p_rig.fisheye;
	cv::Mat mask(lens.height, lens.width, CV_8UC1, cv::Scalar(0));
	const ImageCircle circle = lens_circle(lens);
	cv::circle(mask, cv::Point(int(circle.cx), int(circle.cy)), int(circle.radius * 0.95), cv::Scalar(255), cv::FILLED);
	cv::Mat prev_gray;
	double prev_time = 0.0;
	for (size_t k = 0; k < p_reader.fisheye_count(); k++) {
		const double t = p_reader.get_fisheye_ref(k).timestamp_s;
		if (t + p_rig.fisheye_time_offset_s - p_start > p_options.max_seconds + p_options.search_s) {
			break;
		}
		const FisheyeFrameResult read = p_reader.read_fisheye(k);
		if (!read.ok) {
			r_result->error = read.error;
			return false;
		}
		const cv::Mat gray = gray_8bit(read.frame.image);
		FisheyeStep step;
		if (!prev_gray.empty() && gray.size() == mask.size() && fisheye_step(lens, prev_gray, gray, mask, &step.rotation)) {
			step.t0 = prev_time;
			step.t1 = t;
			r_steps->push_back(step);
		}
		prev_gray = gray;
		prev_time = t;
	}
	return true;
}

// The steps explained over the whole search range (the same steps for every candidate).
std::vector<uint8_t> explained_steps(const std::vector<OrientationRun> &p_runs, const std::vector<FisheyeStep> &p_steps, const glm::dquat &p_extrinsic,
		double p_search_s) {
	std::vector<uint8_t> use(p_steps.size(), 1);
	const std::vector<uint8_t> all(p_steps.size(), 1);
	for (double d = -p_search_s; d <= p_search_s + 1e-9; d += 0.002) {
		const std::vector<glm::dvec3> r = residuals(p_runs, p_steps, p_extrinsic, d, all);
		for (size_t k = 0; k < p_steps.size(); k++) {
			use[k] = use[k] && std::isfinite(r[k].x);
		}
	}
	return use;
}

// The offset of least cost: a grid, then golden-section refinement. p_best: the grid's pick when no
// candidate has a finite cost.
double best_offset(const std::vector<OrientationRun> &p_runs, const std::vector<FisheyeStep> &p_steps, const glm::dquat &p_extrinsic, double p_search_s,
		const std::vector<uint8_t> &p_use, double p_best) {
	double best = p_best;
	double best_cost = std::numeric_limits<double>::infinity();
	size_t n = 0;
	for (double d = -p_search_s; d <= p_search_s + 1e-9; d += 0.002) {
		const double c = cost(residuals(p_runs, p_steps, p_extrinsic, d, p_use), &n);
		if (c < best_cost) {
			best_cost = c;
			best = d;
		}
	}
	double lo = best - 0.002, hi = best + 0.002;
	const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
	while (hi - lo > 5e-5) {
		const double a = hi - phi * (hi - lo), b = lo + phi * (hi - lo);
		if (cost(residuals(p_runs, p_steps, p_extrinsic, a, p_use), &n) < cost(residuals(p_runs, p_steps, p_extrinsic, b, p_use), &n)) {
			hi = b;
		} else {
			lo = a;
		}
	}
	return 0.5 * (lo + hi);
}

// Outliers (a failed step's rotation): beyond 3 MADs of the residual's norm, dropped from r_use.
// p_residuals: those of the used steps. False when there are none.
bool drop_outliers(const std::vector<glm::dvec3> &p_residuals, std::vector<uint8_t> *r_use) {
	std::vector<double> norms;
	for (const glm::dvec3 &v : p_residuals) {
		norms.push_back(glm::length(v)); // finite: every used step is explained at every candidate
	}
	if (norms.empty()) {
		return false;
	}
	std::vector<double> sorted = norms;
	std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
	const double median = sorted[sorted.size() / 2];
	for (double &v : sorted) {
		v = std::abs(v - median);
	}
	std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
	const double limit = median + 3.0 * 1.4826 * std::max(sorted[sorted.size() / 2], 1e-6);
	std::vector<uint8_t> &use = *r_use;
	size_t j = 0;
	for (size_t k = 0; k < use.size(); k++) {
		if (use[k]) {
			use[k] = norms[j++] <= limit;
		}
	}
	return true;
}

// The fit at p_best into r_result: the steps used, the turn, the residual and the standard deviation
// (Gauss-Newton, d residual / d offset by central differences), and the error when it is weak.
void describe_fit(const std::vector<OrientationRun> &p_runs, const std::vector<FisheyeStep> &p_steps, const glm::dquat &p_extrinsic,
		const std::vector<uint8_t> &p_use, double p_best, ClockOffsetEstimate *r_result) {
	ClockOffsetEstimate &result = *r_result;
	size_t n = 0;
	const std::vector<glm::dvec3> r0 = residuals(p_runs, p_steps, p_extrinsic, p_best, p_use);
	const double h = 0.0005;
	const std::vector<glm::dvec3> rp = residuals(p_runs, p_steps, p_extrinsic, p_best + h, p_use), rm = residuals(p_runs, p_steps, p_extrinsic, p_best - h, p_use);
	double jtj = 0.0, sum2 = 0.0;
	for (size_t k = 0; k < r0.size(); k++) {
		const glm::dvec3 j = (rp[k] - rm[k]) / (2.0 * h);
		jtj += glm::dot(j, j);
		sum2 += glm::dot(r0[k], r0[k]);
	}
	cost(r0, &n);
	for (size_t k = 0; k < p_steps.size(); k++) {
		if (p_use[k]) {
			result.turn_deg += 2.0 * std::acos(std::min(1.0, std::abs(p_steps[k].rotation.w))) * DEG;
		}
	}
	result.steps_used = n;
	const double dof = std::max(1.0, 3.0 * double(n) - 1.0);
	result.residual_rms_deg = std::sqrt(sum2 / (3.0 * double(std::max<size_t>(n, 1)))) * DEG;
	result.std_s = jtj > 0.0 ? std::sqrt(sum2 / dof / jtj) : std::numeric_limits<double>::infinity();
	result.offset_s = p_best;
	if (n < 8) {
		result.error = "too few fisheye steps fall within the RGB-D camera's track (" + std::to_string(n) + ")";
	} else if (!(result.std_s < 0.01)) {
		char text[256];
		std::snprintf(text, sizeof(text), "the motion does not fix the offset (%.1f +- %.1f ms over %zu steps, residual %.3f deg): turn the rig by hand, back and forth, while recording",
				p_best * 1000.0, result.std_s * 1000.0, n, result.residual_rms_deg);
		result.error = text;
	}
}

} // namespace

ClockOffsetEstimate estimate_clock_offset(const RecordingReader &p_reader, const Rig &p_rig, const ClockOffsetOptions &p_options) {
	ClockOffsetEstimate result;
	const auto progress = [&](const std::string &p_line) {
		if (p_options.progress) {
			p_options.progress(p_line);
		}
	};
	if (!p_rig.has_fisheye()) {
		result.error = "the rig has no fisheye";
		return result;
	}
	if (p_reader.rgbd_count() < 10 || p_reader.fisheye_count() < 10) {
		result.error = "the recording has too few frames to follow the motion (" + std::to_string(p_reader.rgbd_count()) + " RGB-D, " +
				std::to_string(p_reader.fisheye_count()) + " fisheye; at least 10 of each)";
		return result;
	}
	const double start = p_reader.get_rgbd_ref(0).rgb.timestamp_s;
	std::vector<OrientationRun> runs(1);
	if (!rgbd_orientations(p_reader, p_rig, p_options, start, &runs, &result)) {
		return result;
	}
	progress(std::to_string(result.rgbd_steps) + " RGB-D rotations");
	std::vector<FisheyeStep> steps;
	if (!fisheye_steps(p_reader, p_rig, p_options, start, &steps, &result)) {
		return result;
	}
	result.fisheye_steps = steps.size();
	progress(std::to_string(steps.size()) + " fisheye rotations");
	if (steps.size() < 8 || result.rgbd_steps < 8) {
		result.error = "too few rotations could be measured (" + std::to_string(result.rgbd_steps) + " RGB-D, " + std::to_string(steps.size()) +
				" fisheye): the images need texture and the rig must move";
		return result;
	}
	// 3. The offset: a grid, then golden-section refinement, on the steps explained over the whole
	// search range (the same steps for every candidate); a second pass without the outliers.
	const glm::dquat extrinsic = glm::normalize(p_rig.rgb_from_fisheye.rotation);
	std::vector<uint8_t> use = explained_steps(runs, steps, extrinsic, p_options.search_s);
	double best = 0.0;
	for (int pass = 0; pass < 2; pass++) {
		best = best_offset(runs, steps, extrinsic, p_options.search_s, use, best);
		if (pass == 1 || !drop_outliers(residuals(runs, steps, extrinsic, best, use), &use)) {
			break;
		}
	}
	describe_fit(runs, steps, extrinsic, use, best, &result);
	return result;
}

} // namespace roomprobe
