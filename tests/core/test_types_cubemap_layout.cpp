// The cubemap layout of recordings (docs/recording-format.md, "Cubemaps"): OpenGL/Godot face
// order and pixel-to-direction mapping, and the N x 6N strip.

#include "types/cubemap_layout.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <string>

using namespace roomprobe;

namespace {

void check_direction(const glm::dvec3 &p_actual, const glm::dvec3 &p_expected) {
	const glm::dvec3 expected = glm::normalize(p_expected);
	CHECK(p_actual.x == doctest::Approx(expected.x).epsilon(1e-12));
	CHECK(p_actual.y == doctest::Approx(expected.y).epsilon(1e-12));
	CHECK(p_actual.z == doctest::Approx(expected.z).epsilon(1e-12));
}

} // namespace

TEST_CASE("cubemap face centres look along the six world axes in +X -X +Y -Y +Z -Z order") {
	const int n = 8;
	const double centre = (n - 1) / 2.0; // the pixel coordinate of the face's centre point
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_X, centre, centre, n), glm::dvec3(1, 0, 0));
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_X, centre, centre, n), glm::dvec3(-1, 0, 0));
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_Y, centre, centre, n), glm::dvec3(0, 1, 0));
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_Y, centre, centre, n), glm::dvec3(0, -1, 0));
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_Z, centre, centre, n), glm::dvec3(0, 0, 1));
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_Z, centre, centre, n), glm::dvec3(0, 0, -1));
}

TEST_CASE("cubemap face corners follow the OpenGL table (top row of a side face is +Y)") {
	const int n = 4;
	// The outer corner of the top-left pixel, (-0.5, -0.5): s = t = -1.
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_X, -0.5, -0.5, n), glm::dvec3(1, 1, 1)); // (1, -t, -s)
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_X, -0.5, -0.5, n), glm::dvec3(-1, 1, -1)); // (-1, -t, s)
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_Y, -0.5, -0.5, n), glm::dvec3(-1, 1, -1)); // (s, 1, t)
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_Y, -0.5, -0.5, n), glm::dvec3(-1, -1, 1)); // (s, -1, -t)
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_Z, -0.5, -0.5, n), glm::dvec3(-1, 1, 1)); // (s, -t, 1)
	check_direction(cubemap_direction(CUBEMAP_NEGATIVE_Z, -0.5, -0.5, n), glm::dvec3(1, 1, -1)); // (-s, -t, -1)
	// Bottom-right corner of +Z: s = t = 1.
	check_direction(cubemap_direction(CUBEMAP_POSITIVE_Z, n - 0.5, n - 0.5, n), glm::dvec3(1, -1, 1));
}

TEST_CASE("cubemap_face_pixel inverts cubemap_direction on every face") {
	const int n = 16;
	for (int face = 0; face < 6; face++) {
		for (double v : { 0.0, 3.25, 7.5, 15.0 }) {
			for (double u : { 0.0, 1.5, 9.75, 15.0 }) {
				int back_face = -1;
				double back_u = -1.0;
				double back_v = -1.0;
				cubemap_face_pixel(cubemap_direction(face, u, v, n), n, &back_face, &back_u, &back_v);
				CHECK(back_face == face);
				CHECK(back_u == doctest::Approx(u).epsilon(1e-9));
				CHECK(back_v == doctest::Approx(v).epsilon(1e-9));
			}
		}
	}
	int face = -1;
	double u = 0.0;
	double v = 0.0;
	cubemap_face_pixel(glm::dvec3(0.1, -5.0, 0.2), n, &face, &u, &v);
	CHECK(face == CUBEMAP_NEGATIVE_Y);
	CHECK(std::string(cubemap_face_name(face)) == "-Y");
}

TEST_CASE("cubemap strip stacks the faces top to bottom and splits back") {
	CubemapFaces faces;
	for (int f = 0; f < 6; f++) {
		faces[f] = cv::Mat(4, 4, CV_32FC3, cv::Scalar(f, 10 * f, 100 * f));
	}
	faces[CUBEMAP_NEGATIVE_Y].at<cv::Vec3f>(1, 2) = cv::Vec3f(7, 8, 9);
	const cv::Mat strip = cubemap_faces_to_strip(faces);
	REQUIRE(strip.cols == 4);
	REQUIRE(strip.rows == 24);
	for (int f = 0; f < 6; f++) {
		CHECK(strip.at<cv::Vec3f>(f * 4, 0)[1] == float(10 * f));
	}
	CHECK(strip.at<cv::Vec3f>(CUBEMAP_NEGATIVE_Y * 4 + 1, 2) == cv::Vec3f(7, 8, 9));
	const CubemapFaces back = cubemap_strip_to_faces(strip);
	CHECK(back[CUBEMAP_NEGATIVE_Y].at<cv::Vec3f>(1, 2) == cv::Vec3f(7, 8, 9));
	CHECK(back[CUBEMAP_POSITIVE_Z].at<cv::Vec3f>(3, 3) == cv::Vec3f(4, 40, 400));

	faces[3] = cv::Mat(5, 5, CV_32FC3); // not the same size
	CHECK(cubemap_faces_to_strip(faces).empty());
	CHECK(cubemap_strip_to_faces(cv::Mat(20, 4, CV_32FC3))[0].empty());
}
