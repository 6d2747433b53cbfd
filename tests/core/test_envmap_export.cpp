// Writing environment maps: the EXR strip of recordings, and the 8-bit horizontal-cross net.

#include <io/opencv.h>

#include "envmap/export.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <glm/geometric.hpp>

#include <filesystem>
#include <string>

using namespace roomprobe;

namespace {

std::filesystem::path scratch_folder(const std::string &p_name) {
	const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("roomprobe-test-envmap-" + p_name);
	std::filesystem::remove_all(folder);
	std::filesystem::create_directories(folder);
	return folder;
}

} // namespace

TEST_CASE("a cubemap round-trips through its EXR strip exactly") {
	const std::filesystem::path folder = scratch_folder("exr");
	Cubemap cubemap = make_cubemap(16);
	cv::RNG rng(5);
	for (cv::Mat &face : cubemap.faces) {
		rng.fill(face, cv::RNG::UNIFORM, cv::Scalar::all(-1.0), cv::Scalar::all(1000.0));
	}
	const std::string path = (folder / "probe.exr").string();
	REQUIRE(write_cubemap_exr(path, cubemap) == "");
	Cubemap back;
	REQUIRE(read_cubemap_exr(path, &back) == "");
	REQUIRE(back.size == 16);
	REQUIRE(is_valid_cubemap(back));
	for (size_t f = 0; f < 6; f++) {
		CHECK(cv::norm(cubemap.faces[f], back.faces[f], cv::NORM_INF) == 0.0);
	}
	// The file is the recordings' N x 6N strip.
	cv::Mat strip = cubemap_faces_to_strip(cubemap.faces);
	CHECK(strip.rows == 6 * 16);
	// Errors name the file and nothing throws.
	CHECK(write_cubemap_exr((folder / "bad.exr").string(), Cubemap()).find("bad.exr") != std::string::npos);
	CHECK(read_cubemap_exr((folder / "missing.exr").string(), &back).find("missing") != std::string::npos);
	CHECK(write_cubemap_exr((folder / "no-such-folder" / "x.exr").string(), cubemap) != "");
	std::filesystem::remove_all(folder);
}

TEST_CASE("the PNG net is a 4N x 3N horizontal cross, tone mapped to sRGB") {
	CHECK(tone_map_srgb8(0.0f) == 0);
	CHECK(tone_map_srgb8(-3.0f) == 0);
	CHECK(tone_map_srgb8(1.0f) == 255);
	CHECK(tone_map_srgb8(7.0f) == 255);
	CHECK(tone_map_srgb8(0.5f) == 188); // sRGB of linear 0.5
	CHECK(tone_map_srgb8(0.001f) == 3); // the linear toe: 12.92 x

	const int n = 8;
	Cubemap cubemap = make_cubemap(n);
	for (int f = 0; f < 6; f++) {
		cubemap.faces[size_t(f)].setTo(cv::Scalar(0.1 * (f + 1), 0.05 * f, 1.0 - 0.1 * f));
	}
	const std::filesystem::path folder = scratch_folder("png");
	const std::string path = (folder / "net.png").string();
	REQUIRE(write_cubemap_png_net(path, cubemap) == "");
	const cv::Mat bgr = cv::imread(path, cv::IMREAD_UNCHANGED);
	REQUIRE(bgr.type() == CV_8UC3);
	CHECK(bgr.cols == 4 * n);
	CHECK(bgr.rows == 3 * n);
	cv::Mat rgb;
	cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
	// Expected placement: +Y above +Z; -X, +Z, +X, -Z across the middle; -Y below +Z.
	const int columns[6] = { 2, 0, 1, 1, 1, 3 };
	const int rows[6] = { 1, 1, 0, 2, 1, 1 };
	for (int f = 0; f < 6; f++) {
		int column = -1;
		int row = -1;
		cubemap_net_cell(f, &column, &row);
		CHECK(column == columns[f]);
		CHECK(row == rows[f]);
		const cv::Vec3f linear = cubemap.faces[size_t(f)].at<cv::Vec3f>(0, 0);
		const cv::Vec3b expected(tone_map_srgb8(linear[0]), tone_map_srgb8(linear[1]), tone_map_srgb8(linear[2]));
		for (int y = 0; y < n; y++) {
			for (int x = 0; x < n; x++) {
				CHECK(rgb.at<cv::Vec3b>(row * n + y, column * n + x) == expected);
			}
		}
	}
	// Empty cells are black.
	CHECK(rgb.at<cv::Vec3b>(0, 0) == cv::Vec3b(0, 0, 0));
	CHECK(rgb.at<cv::Vec3b>(2 * n + 1, 3 * n + 1) == cv::Vec3b(0, 0, 0));
	// The cross folds into the cube: neighbouring edge pixels look in nearby directions.
	const auto close = [&](int p_fa, double p_ua, double p_va, int p_fb, double p_ub, double p_vb) {
		return glm::length(cubemap_direction(p_fa, p_ua, p_va, n) - cubemap_direction(p_fb, p_ub, p_vb, n)) < 0.2;
	};
	for (int i = 0; i < n; i++) {
		CHECK(close(CUBEMAP_POSITIVE_Y, i, n - 1, CUBEMAP_POSITIVE_Z, i, 0)); // +Y bottom / +Z top
		CHECK(close(CUBEMAP_POSITIVE_Z, i, n - 1, CUBEMAP_NEGATIVE_Y, i, 0)); // +Z bottom / -Y top
		CHECK(close(CUBEMAP_NEGATIVE_X, n - 1, i, CUBEMAP_POSITIVE_Z, 0, i)); // -X right / +Z left
		CHECK(close(CUBEMAP_POSITIVE_Z, n - 1, i, CUBEMAP_POSITIVE_X, 0, i)); // +Z right / +X left
		CHECK(close(CUBEMAP_POSITIVE_X, n - 1, i, CUBEMAP_NEGATIVE_Z, 0, i)); // +X right / -Z left
	}
	CHECK(cubemap_net_image(Cubemap()).empty());
	std::filesystem::remove_all(folder);
}
