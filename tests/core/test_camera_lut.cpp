// Look-up-table views of a fisheye image (camera/lut_views.h), for display and debugging.

#include "camera/lut_views.h"
#include "camera/omni_camera.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace roomprobe;

namespace {

// A 185-degree lens whose whole image circle lies on the sensor (xi = 1: r = f tan(theta / 2)).
// Its k1 pulls the rim inwards, so here max_angle_deg, not the circle, bounds what it sees.
OmniParams full_circle_fisheye() {
	OmniParams params;
	params.width = params.height = 1000;
	params.xi = 1.0;
	params.fx = params.fy = 470.0 / std::tan(92.5 * std::numbers::pi / 360.0);
	params.cx = params.cy = params.circle_cx = params.circle_cy = 499.5;
	params.circle_radius = 470.0;
	params.k1 = -0.01;
	params.max_angle_deg = 92.5;
	return params;
}

} // namespace

TEST_CASE("lut views: a perspective view looks along the rotated axis and maps through project_omni") {
	const OmniParams params = full_circle_fisheye();
	// Look 60 degrees to the right of the optical axis (a rotation about the camera's y).
	const double a = 60.0 * std::numbers::pi / 180.0;
	const glm::dmat3 camera_from_view(std::cos(a), 0.0, -std::sin(a), 0.0, 1.0, 0.0, std::sin(a), 0.0, std::cos(a));
	const LutView view = build_perspective_lut(params, 301, 201, 90.0, camera_from_view);
	REQUIRE(view.map_x.size() == cv::Size(301, 201));
	glm::dvec2 expected;
	REQUIRE(project_omni(params, { std::sin(a), 0.0, std::cos(a) }, &expected));
	CHECK(view.map_x.at<float>(100, 150) == doctest::Approx(expected.x).epsilon(1e-6));
	CHECK(view.map_y.at<float>(100, 150) == doctest::Approx(expected.y).epsilon(1e-6));
	CHECK(view.map_x.at<float>(100, 150) > params.cx);

	// Its right edge looks 105 degrees off the axis, beyond the lens: masked, and every pixel is
	// either valid with a source pixel inside the circle, or masked with -1.
	int masked = 0;
	for (int row = 0; row < view.mask.rows; row++) {
		for (int column = 0; column < view.mask.cols; column++) {
			const glm::dvec2 source(view.map_x.at<float>(row, column), view.map_y.at<float>(row, column));
			if (view.mask.at<uint8_t>(row, column)) {
				CHECK(omni_pixel_valid(params, source));
			} else {
				masked++;
				CHECK(source == glm::dvec2(-1.0, -1.0));
			}
		}
	}
	CHECK(view.mask.at<uint8_t>(100, 300) == 0);
	CHECK(masked > 0);
}

TEST_CASE("lut views: an equirectangular view covers the lens's 185-degree cap of the sphere") {
	const OmniParams params = full_circle_fisheye();
	const LutView view = build_equirect_lut(params, 720, 360);
	std::mt19937 rng(7);
	std::uniform_int_distribution<int> column(0, 719), row(0, 359);
	for (int i = 0; i < 200; i++) {
		const glm::dvec2 pixel(column(rng), row(rng));
		glm::dvec2 expected;
		const bool seen = project_omni(params, equirect_direction(720, 360, pixel), &expected) && omni_pixel_valid(params, expected);
		CHECK((view.mask.at<uint8_t>(int(pixel.y), int(pixel.x)) != 0) == seen);
		if (seen) {
			CHECK(view.map_x.at<float>(int(pixel.y), int(pixel.x)) == doctest::Approx(expected.x).epsilon(1e-6));
		}
	}
	// The valid pixels, weighted by their solid angle (cos latitude), are the cap's share of the
	// sphere: (1 - cos 92.5 degrees) / 2.
	double seen = 0.0, all = 0.0;
	for (int r = 0; r < 360; r++) {
		const double weight = std::cos((0.5 - (r + 0.5) / 360.0) * std::numbers::pi);
		for (int c = 0; c < 720; c++) {
			seen += view.mask.at<uint8_t>(r, c) ? weight : 0.0;
			all += weight;
		}
	}
	const double expected_share = 0.5 * (1.0 - std::cos(92.5 * std::numbers::pi / 180.0));
	MESSAGE("share of the sphere seen: " << seen / all << " (a 185-degree cap: " << expected_share << ")");
	CHECK(seen / all == doctest::Approx(expected_share).epsilon(0.01));
	// The view's centre looks along the optical axis.
	CHECK(view.map_x.at<float>(180, 360) == doctest::Approx(params.cx).epsilon(0.01));

	// apply_lut samples the image and leaves the masked pixels black.
	const cv::Mat white(params.height, params.width, CV_8UC1, cv::Scalar(255));
	const cv::Mat remapped = apply_lut(white, view);
	CHECK(remapped.at<uint8_t>(180, 360) == 255);
	CHECK(remapped.at<uint8_t>(180, 0) == 0); // straight behind
	CHECK(cv::countNonZero(remapped) <= cv::countNonZero(view.mask));
}
