// The paper's baseline environment map (§5.3): fisheye frames rotated into the cubemap,
// translation ignored, accumulated over frames.

#include <io/opencv.h>

#include "camera/omni_camera.h"
#include "envmap/baseline.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <numbers>

using namespace roomprobe;

namespace {

constexpr double k_deg = std::numbers::pi / 180.0;

// A 185-degree fisheye: xi = 1, r = f tan(theta / 2), 190 px at 92.5 degrees.
OmniParams small_fisheye() {
	OmniParams params;
	params.width = 400;
	params.height = 400;
	params.xi = 1.0;
	params.fx = params.fy = 190.0 / std::tan(0.5 * 92.5 * k_deg);
	params.cx = params.circle_cx = 199.5;
	params.cy = params.circle_cy = 199.5;
	params.circle_radius = 190.0;
	params.max_angle_deg = 92.5;
	return params;
}

// Distinct 8-bit face colours (R, G, B).
const cv::Vec3b k_face_colours[6] = { { 200, 20, 20 }, { 20, 200, 20 }, { 20, 20, 200 }, { 200, 200, 20 }, { 20, 200, 200 }, { 200, 20, 200 } };

// What a fisheye at any position with rotation world_from_fisheye sees of a distant
// environment whose colour is that of the cubemap face each direction falls on.
cv::Mat fisheye_of_face_colours(const OmniParams &p_params, const glm::dquat &p_world_from_fisheye) {
	cv::Mat image(p_params.height, p_params.width, CV_8UC3, cv::Scalar::all(0));
	for (int y = 0; y < image.rows; y++) {
		for (int x = 0; x < image.cols; x++) {
			glm::dvec3 ray;
			if (!unproject_omni(p_params, glm::dvec2(x, y), &ray)) {
				continue;
			}
			int face = 0;
			double u = 0.0;
			double v = 0.0;
			cubemap_face_pixel(p_world_from_fisheye * ray, 8, &face, &u, &v);
			image.at<cv::Vec3b>(y, x) = k_face_colours[face];
		}
	}
	return image;
}

// The fisheye looking straight up: its optical axis (camera +z) along world +Y.
glm::dquat looking_up() {
	return glm::angleAxis(-0.5 * std::numbers::pi, glm::dvec3(1.0, 0.0, 0.0));
}

void check_colour(const Cubemap &p_cubemap, int p_face, int p_u, int p_v, const cv::Vec3b &p_expected) {
	const cv::Vec3f c = p_cubemap.faces[size_t(p_face)].at<cv::Vec3f>(p_v, p_u);
	for (int k = 0; k < 3; k++) {
		CHECK(c[k] == doctest::Approx(p_expected[k] / 255.0).epsilon(1e-5));
	}
}

} // namespace

TEST_CASE("the baseline recovers the upper hemisphere's face colours from one upward fisheye frame") {
	const OmniParams params = small_fisheye();
	// Yawed and far from the probe: the baseline uses the rotation only.
	Pose pose;
	pose.rotation = glm::angleAxis(0.6, glm::dvec3(0.0, 1.0, 0.0)) * looking_up();
	pose.translation = glm::dvec3(3.0, 1.5, -2.0);
	const cv::Mat image = fisheye_of_face_colours(params, pose.rotation);
	const int n = 32;
	BaselineEnvmap baseline(n);
	CHECK(baseline.seen_fraction() == 0.0);
	const int written = baseline.add_frame(image, params, pose);
	CHECK(written > 0);
	const Cubemap &cubemap = baseline.cubemap();
	REQUIRE(cubemap.size == n);
	// The whole +Y face, away from its edges (where bilinear sampling mixes neighbours).
	for (int v = 3; v < n - 3; v++) {
		for (int u = 3; u < n - 3; u++) {
			check_colour(cubemap, CUBEMAP_POSITIVE_Y, u, v, k_face_colours[CUBEMAP_POSITIVE_Y]);
		}
	}
	// The side faces above the horizon (rows with direction y > 0.1), away from the side edges.
	for (int face : { CUBEMAP_POSITIVE_X, CUBEMAP_NEGATIVE_X, CUBEMAP_POSITIVE_Z, CUBEMAP_NEGATIVE_Z }) {
		for (int v = 3; v < n; v++) {
			for (int u = 3; u < n - 3; u++) {
				if (cubemap_direction(face, u, v, n).y > 0.1) {
					CHECK(baseline.seen()[size_t(face)].at<uint8_t>(v, u) == 255);
					check_colour(cubemap, face, u, v, k_face_colours[face]);
				} else if (cubemap_direction(face, u, v, n).y < -0.1) {
					CHECK(baseline.seen()[size_t(face)].at<uint8_t>(v, u) == 0); // beyond 92.5 degrees
				}
			}
		}
	}
	// The lower hemisphere is never seen and stays black.
	CHECK(cv::countNonZero(baseline.seen()[CUBEMAP_NEGATIVE_Y]) == 0);
	CHECK(cv::norm(cubemap.faces[CUBEMAP_NEGATIVE_Y]) == 0.0);
	CHECK(baseline.seen_fraction() == doctest::Approx(0.5 * (1.0 - std::cos(92.5 * k_deg))).epsilon(0.03));
}

TEST_CASE("the baseline ignores translation, keeps old texels and overwrites with the latest frame") {
	const OmniParams params = small_fisheye();
	const int n = 16;
	Pose up;
	up.rotation = looking_up();
	const cv::Mat image = fisheye_of_face_colours(params, up.rotation);
	BaselineEnvmap a(n);
	BaselineEnvmap b(n);
	a.add_frame(image, params, up);
	Pose moved = up;
	moved.translation = glm::dvec3(10.0, -4.0, 2.0);
	b.add_frame(image, params, moved);
	for (int face = 0; face < 6; face++) {
		CHECK(cv::norm(a.cubemap().faces[size_t(face)], b.cubemap().faces[size_t(face)], cv::NORM_INF) == 0.0);
	}
	// A second frame looking sideways (along world +X) adds the +X side's lower half, leaves the
	// -X side's texels as the first frame wrote them, and overwrites what it sees with its own image.
	Pose side;
	side.rotation = glm::angleAxis(0.5 * std::numbers::pi, glm::dvec3(0.0, 1.0, 0.0)); // camera +z -> world +X
	const double before = a.seen_fraction();
	const cv::Mat grey(params.height, params.width, CV_8UC1, cv::Scalar::all(51));
	a.add_frame(grey, params, side);
	CHECK(a.seen_fraction() > before);
	const glm::dvec3 down_x = glm::normalize(glm::dvec3(1.0, -0.5, 0.0));
	int face = 0;
	double u = 0.0;
	double v = 0.0;
	cubemap_face_pixel(down_x, n, &face, &u, &v);
	CHECK(a.seen()[size_t(face)].at<uint8_t>(int(v), int(u)) == 255);
	check_colour(a.cubemap(), face, int(u), int(v), cv::Vec3b(51, 51, 51));
	check_colour(a.cubemap(), CUBEMAP_NEGATIVE_X, n / 2, 2, k_face_colours[CUBEMAP_NEGATIVE_X]);
	// Wrong image sizes or types are refused.
	CHECK(a.add_frame(cv::Mat(10, 10, CV_8UC3), params, side) == 0);
	CHECK(a.add_frame(cv::Mat(params.height, params.width, CV_16UC1), params, side) == 0);
	a.clear();
	CHECK(a.seen_fraction() == 0.0);
}
