// The unified omnidirectional model (camera/omni_camera.h), against cv::omnidir, which defines it,
// on a 185-degree lens with xi near 1 that sees beyond 90 degrees off its axis.

#include "camera/omni_camera.h"
#include "io/opencv.h"

#include <doctest/doctest.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/ccalib/omnidir.hpp>
#pragma GCC diagnostic pop

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace roomprobe;

namespace {

constexpr double k_half_fov_deg = 92.5; // a 185-degree lens
constexpr double k_deg = std::numbers::pi / 180.0;

// A 185-degree fisheye on a 1280x900 sensor, made so that the rim of its field of view is the
// image circle: with xi = 1 and no distortion the unified model is r = f tan(theta / 2), so a
// circle of 470 px at 92.5 degrees needs f = 470 / tan(46.25 degrees). The sensor crops the circle
// (940 px across) at the top and bottom.
OmniParams fisheye_185() {
	OmniParams params;
	params.width = 1280;
	params.height = 900;
	params.xi = 1.0;
	params.fx = params.fy = 470.0 / std::tan(0.5 * k_half_fov_deg * k_deg);
	params.cx = params.circle_cx = 639.5;
	params.cy = params.circle_cy = 449.5;
	params.circle_radius = 470.0;
	return params;
}

// A realistic fitted lens: xi a little off 1, skew, all four distortion terms, off-centre.
OmniParams distorted_fisheye() {
	OmniParams params;
	params.width = 1280;
	params.height = 960;
	params.xi = 0.94;
	params.fx = 433.0;
	params.fy = 431.5;
	params.cx = 641.3;
	params.cy = 477.8;
	params.skew = 0.7;
	params.k1 = -0.12;
	params.k2 = 0.025;
	params.p1 = 3e-4;
	params.p2 = -2e-4;
	return params;
}

// Random points up to p_max_angle_deg off the axis (uniform over that cap of the sphere), at
// 0.2 to 10 m.
std::vector<glm::dvec3> random_points(double p_max_angle_deg, int p_count, unsigned p_seed) {
	std::mt19937 rng(p_seed);
	std::uniform_real_distribution<double> cos_theta(std::cos(p_max_angle_deg * k_deg), 1.0), phi(0.0, 2.0 * std::numbers::pi),
			distance(0.2, 10.0);
	std::vector<glm::dvec3> points;
	for (int i = 0; i < p_count; i++) {
		const double c = cos_theta(rng), s = std::sqrt(1.0 - c * c), a = phi(rng);
		points.push_back(distance(rng) * glm::dvec3(s * std::cos(a), s * std::sin(a), c));
	}
	return points;
}

double angle_between(const glm::dvec3 &p_a, const glm::dvec3 &p_b) {
	return std::atan2(glm::length(glm::cross(p_a, p_b)), glm::dot(p_a, p_b));
}

OmniParams unlimited(OmniParams p_params) {
	p_params.circle_radius = 0.0;
	p_params.max_angle_deg = 0.0;
	return p_params;
}

} // namespace

TEST_CASE("omni camera: project_omni agrees with cv::omnidir::projectPoints to 1e-6 px, beyond 90 degrees too") {
	for (const OmniParams &params : { fisheye_185(), distorted_fisheye() }) {
		const std::vector<glm::dvec3> points = random_points(k_half_fov_deg, 2000, 3);
		cv::Mat cv_points(1, int(points.size()), CV_64FC3);
		for (size_t i = 0; i < points.size(); i++) {
			cv_points.at<cv::Vec3d>(0, int(i)) = cv::Vec3d(points[i].x, points[i].y, points[i].z);
		}
		const cv::Matx33d k(params.fx, params.skew, params.cx, 0.0, params.fy, params.cy, 0.0, 0.0, 1.0);
		const cv::Vec4d distortion(params.k1, params.k2, params.p1, params.p2);
		cv::Mat expected;
		cv::omnidir::projectPoints(cv_points, expected, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, params.xi, distortion);
		double worst = 0.0;
		int behind = 0;
		for (size_t i = 0; i < points.size(); i++) {
			glm::dvec2 pixel;
			REQUIRE(project_omni(unlimited(params), points[i], &pixel));
			const cv::Vec2d e = expected.at<cv::Vec2d>(0, int(i));
			worst = std::max(worst, glm::length(pixel - glm::dvec2(e[0], e[1])));
			behind += points[i].z < 0.0;
		}
		MESSAGE("xi " << params.xi << ": largest difference from cv::omnidir over " << points.size() << " points (" << behind
					  << " with z < 0): " << worst << " px");
		CHECK(behind > 10);
		CHECK(worst < 1e-6);
	}
}

TEST_CASE("omni camera: unproject_omni inverts project_omni to 1e-9 rad and gives unit rays") {
	for (const OmniParams &params : { fisheye_185(), distorted_fisheye() }) {
		double worst = 0.0, worst_norm = 0.0;
		int behind = 0;
		for (const glm::dvec3 &point : random_points(k_half_fov_deg, 2000, 4)) {
			glm::dvec2 pixel;
			REQUIRE(project_omni(unlimited(params), point, &pixel));
			glm::dvec3 ray;
			REQUIRE(unproject_omni(unlimited(params), pixel, &ray));
			worst = std::max(worst, angle_between(ray, point));
			worst_norm = std::max(worst_norm, std::abs(glm::length(ray) - 1.0));
			behind += ray.z < 0.0;
		}
		MESSAGE("xi " << params.xi << ": largest round-trip direction error " << worst << " rad (" << behind << " rays with z < 0)");
		CHECK(behind > 10);
		CHECK(worst < 1e-9);
		CHECK(worst_norm < 1e-12);
	}
	// xi > 1 (a catadioptric-like lens) keeps to the branch before the fold, and rejects the rest.
	OmniParams wide = unlimited(distorted_fisheye());
	wide.xi = 1.6;
	wide.k1 = wide.k2 = wide.p1 = wide.p2 = 0.0;
	const double fold_deg = std::acos(-1.0 / wide.xi) / k_deg; // 128.7 degrees
	double worst = 0.0;
	for (const glm::dvec3 &point : random_points(fold_deg - 1.0, 1000, 5)) {
		glm::dvec2 pixel;
		glm::dvec3 ray;
		REQUIRE(project_omni(wide, point, &pixel));
		REQUIRE(unproject_omni(wide, pixel, &ray));
		worst = std::max(worst, angle_between(ray, point));
	}
	CHECK(worst < 1e-9);
	glm::dvec2 pixel;
	const double beyond = (fold_deg + 1.0) * k_deg;
	CHECK_FALSE(project_omni(wide, { std::sin(beyond), 0.0, std::cos(beyond) }, &pixel));
}

TEST_CASE("omni camera: no pixel for what the model cannot see") {
	OmniParams params = unlimited(fisheye_185());
	params.xi = 0.8; // has no projection where z <= -0.8 |p|
	glm::dvec2 pixel(-7.0, -7.0);
	CHECK_FALSE(project_omni(params, { 0.0, 0.0, 0.0 }, &pixel));
	CHECK_FALSE(project_omni(params, { 0.0, 0.0, -1.0 }, &pixel));
	CHECK_FALSE(project_omni(params, { 0.5, 0.0, -0.9 }, &pixel)); // z / |p| = -0.87
	CHECK_FALSE(project_omni(params, { std::nan(""), 0.0, 1.0 }, &pixel));
	CHECK(pixel == glm::dvec2(-7.0, -7.0)); // untouched
	CHECK(project_omni(params, { 0.9, 0.0, -0.5 }, &pixel)); // z / |p| = -0.49

	// max_angle_deg alone bounds both directions.
	params.max_angle_deg = 80.0;
	const double inside = 79.9 * k_deg, outside = 80.1 * k_deg;
	REQUIRE(project_omni(params, { std::sin(inside), 0.0, std::cos(inside) }, &pixel));
	glm::dvec3 ray;
	CHECK(unproject_omni(params, pixel, &ray));
	CHECK_FALSE(project_omni(params, { 0.0, std::sin(outside), std::cos(outside) }, &pixel));
	OmniParams no_limit = params;
	no_limit.max_angle_deg = 0.0;
	REQUIRE(project_omni(no_limit, { 0.0, std::sin(outside), std::cos(outside) }, &pixel));
	CHECK_FALSE(unproject_omni(params, pixel, &ray));
}

TEST_CASE("omni camera: pixels outside the image circle or the image are rejected") {
	const OmniParams params = fisheye_185();
	const glm::dvec2 centre(params.circle_cx, params.circle_cy);
	glm::dvec3 ray;
	for (int i = 0; i < 360; i++) {
		const glm::dvec2 direction(std::cos(i * k_deg), std::sin(i * k_deg));
		const glm::dvec2 just_inside = centre + (params.circle_radius - 0.01) * direction;
		const glm::dvec2 just_outside = centre + (params.circle_radius + 0.01) * direction;
		const bool in_image = just_inside.y >= -0.5 && just_inside.y <= params.height - 0.5;
		CHECK(omni_pixel_valid(params, just_inside) == in_image);
		CHECK(unproject_omni(params, just_inside, &ray)); // the circle bounds unproject_omni, not the image
		CHECK_FALSE(omni_pixel_valid(params, just_outside));
		CHECK_FALSE(unproject_omni(params, just_outside, &ray));
	}
	// The image's corners are outside the circle; a pixel inside the circle but off the image is
	// not a valid pixel, though it has a ray.
	CHECK_FALSE(omni_pixel_valid(params, { 0.0, 0.0 }));
	CHECK_FALSE(unproject_omni(params, { 1279.0, 899.0 }, &ray));
	CHECK_FALSE(omni_pixel_valid(params, { 639.5, -1.0 }));
	CHECK(unproject_omni(params, { 639.5, -1.0 }, &ray));
	CHECK_FALSE(omni_pixel_valid(params, { std::nan(""), 449.5 }));
	CHECK(omni_pixel_valid(params, { 639.5, -0.5 }));
	CHECK(omni_pixel_valid(params, { 639.5, 899.5 }));
	CHECK_FALSE(omni_pixel_valid(params, { 639.5, 900.0 }));
	CHECK(omni_pixel_valid(params, centre));
	REQUIRE(unproject_omni(params, centre, &ray));
	CHECK(angle_between(ray, { 0.0, 0.0, 1.0 }) < 1e-12);
	// And project_omni gives no pixel for a ray that lands outside the circle.
	glm::dvec2 pixel;
	const double outside = (k_half_fov_deg + 0.1) * k_deg;
	CHECK_FALSE(project_omni(params, { std::sin(outside), 0.0, std::cos(outside) }, &pixel));
}

TEST_CASE("omni camera: the constructed lens sees 185 degrees") {
	// The field of view as the model and its circle give it: in each azimuth, bisect for the
	// largest angle off the axis that project_omni still maps inside the circle.
	const OmniParams params = fisheye_185();
	double smallest = 180.0, largest = 0.0;
	for (int azimuth = 0; azimuth < 360; azimuth += 15) {
		const double a = azimuth * k_deg;
		double seen = 0.0, unseen = std::numbers::pi;
		for (int step = 0; step < 60; step++) {
			const double theta = 0.5 * (seen + unseen);
			glm::dvec2 pixel;
			const bool ok = project_omni(params, { std::sin(theta) * std::cos(a), std::sin(theta) * std::sin(a), std::cos(theta) }, &pixel);
			(ok ? seen : unseen) = theta;
		}
		smallest = std::min(smallest, seen / k_deg);
		largest = std::max(largest, seen / k_deg);
	}
	MESSAGE("field of view: " << 2.0 * smallest << " to " << 2.0 * largest << " degrees");
	CHECK(2.0 * smallest == doctest::Approx(185.0).epsilon(1e-9));
	CHECK(2.0 * largest == doctest::Approx(185.0).epsilon(1e-9));
}
