// The pinhole camera with OpenCV's radial-tangential distortion (camera/pinhole_camera.h), against
// cv::projectPoints, which defines the model.

#include "io/opencv.h"
#include "camera/pinhole_camera.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace roomprobe;

namespace {

// An Xtion/Kinect-like RGB camera, 640x480, with the strong radial terms such calibrations give.
PinholeParams kinect_like() {
	PinholeParams params;
	params.width = 640;
	params.height = 480;
	params.fx = 525.3;
	params.fy = 524.8;
	params.cx = 319.6;
	params.cy = 241.2;
	params.k1 = 0.2624;
	params.k2 = -0.9531;
	params.p1 = -0.0054;
	params.p2 = 0.0026;
	params.k3 = 1.1633;
	return params;
}

// Points in front of the camera whose rays pass through the image or up to 10% beyond its edges
// (where the distortion above is still monotonic), at 0.3 to 8 m.
std::vector<glm::dvec3> random_points_in_view(const PinholeParams &p_params, int p_count, unsigned p_seed) {
	std::mt19937 rng(p_seed);
	const double half_w = 0.55 * p_params.width / p_params.fx, half_h = 0.55 * p_params.height / p_params.fy;
	std::uniform_real_distribution<double> x(-half_w, half_w), y(-half_h, half_h), depth(0.3, 8.0);
	std::vector<glm::dvec3> points;
	for (int i = 0; i < p_count; i++) {
		const double z = depth(rng);
		points.push_back({ x(rng) * z, y(rng) * z, z });
	}
	return points;
}

double angle_between(const glm::dvec3 &p_a, const glm::dvec3 &p_b) {
	// atan2 of |a x b| and a.b: accurate for tiny angles, where acos is not.
	return std::atan2(glm::length(glm::cross(p_a, p_b)), glm::dot(p_a, p_b));
}

} // namespace

TEST_CASE("pinhole camera: project_pinhole agrees with cv::projectPoints to 1e-6 px") {
	const PinholeParams params = kinect_like();
	const std::vector<glm::dvec3> points = random_points_in_view(params, 1000, 1);
	std::vector<cv::Point3d> cv_points;
	for (const glm::dvec3 &p : points) {
		cv_points.emplace_back(p.x, p.y, p.z);
	}
	const cv::Matx33d k(params.fx, 0.0, params.cx, 0.0, params.fy, params.cy, 0.0, 0.0, 1.0);
	const std::vector<double> distortion = { params.k1, params.k2, params.p1, params.p2, params.k3 };
	std::vector<cv::Point2d> expected;
	cv::projectPoints(cv_points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, distortion, expected);
	double worst = 0.0;
	for (size_t i = 0; i < points.size(); i++) {
		glm::dvec2 pixel;
		REQUIRE(project_pinhole(params, points[i], &pixel));
		worst = std::max(worst, glm::length(pixel - glm::dvec2(expected[i].x, expected[i].y)));
	}
	MESSAGE("largest difference from cv::projectPoints over 1000 points: " << worst << " px");
	CHECK(worst < 1e-6);
}

TEST_CASE("pinhole camera: unproject_pinhole inverts project_pinhole to 1e-9 rad") {
	const PinholeParams params = kinect_like();
	double worst = 0.0;
	for (const glm::dvec3 &point : random_points_in_view(params, 1000, 2)) {
		glm::dvec2 pixel;
		REQUIRE(project_pinhole(params, point, &pixel));
		const glm::dvec3 ray = unproject_pinhole(params, pixel);
		CHECK(ray.z == 1.0);
		worst = std::max(worst, angle_between(ray, point));
	}
	MESSAGE("largest round-trip direction error: " << worst << " rad");
	CHECK(worst < 1e-9);

	// Without distortion the ray is the pinhole's plain inverse.
	PinholeParams plain = params;
	plain.k1 = plain.k2 = plain.p1 = plain.p2 = plain.k3 = 0.0;
	const glm::dvec3 ray = unproject_pinhole(plain, { plain.cx + plain.fx * 0.25, plain.cy - plain.fy * 0.5 });
	CHECK(ray.x == doctest::Approx(0.25).epsilon(1e-12));
	CHECK(ray.y == doctest::Approx(-0.5).epsilon(1e-12));
}

TEST_CASE("pinhole camera: points on or behind the camera plane have no pixel") {
	const PinholeParams params = kinect_like();
	glm::dvec2 pixel(-7.0, -7.0);
	CHECK_FALSE(project_pinhole(params, { 0.1, 0.2, -1.0 }, &pixel));
	CHECK_FALSE(project_pinhole(params, { 0.0, 0.0, -1e-9 }, &pixel));
	CHECK_FALSE(project_pinhole(params, { 1.0, 1.0, 0.0 }, &pixel));
	CHECK_FALSE(project_pinhole(params, { 0.0, 0.0, std::nan("") }, &pixel));
	CHECK(pixel == glm::dvec2(-7.0, -7.0)); // untouched
	REQUIRE(project_pinhole(params, { 0.0, 0.0, 1e-9 }, &pixel));
	CHECK(pixel.x == doctest::Approx(params.cx));
	CHECK(pixel.y == doctest::Approx(params.cy));
}
