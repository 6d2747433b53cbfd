// io/radiance_hdr: Radiance .hdr files read without OpenCV's imgcodecs, checked against
// cv::imread on the real panoramas (bit for bit), against small files made here, flat and
// run-length coded, and against broken ones; and synth's load_panorama, which reads through it.
#include "io/image_codec.h"
#include "io/opencv.h"
#include "io/radiance_hdr.h"
#include "recording/recording_io.h"
#include "synth/synth_scene.h"

#include <doctest/doctest.h>

// OpenCV's codecs, as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

using namespace roomprobe;

namespace {

using Rgbe = std::array<uint8_t, 4>;

// A width x height image of RGBE pixels: run-friendly on the left (the same pixel), varied on the right.
std::vector<Rgbe> test_pixels(int p_width, int p_height) {
	std::vector<Rgbe> pixels;
	for (int y = 0; y < p_height; ++y) {
		for (int x = 0; x < p_width; ++x) {
			if (x < p_width / 2) {
				pixels.push_back({ 128, 64, 255, 129 }); // 1, 0.5, 1.9921875
			} else {
				pixels.push_back({ uint8_t(17 * x + y), uint8_t(200 - x), uint8_t(3 * y), uint8_t(x == p_width - 1 ? 0 : 120 + x + y) });
			}
		}
	}
	return pixels;
}

std::string header(int p_width, int p_height, const std::string &p_extra = "") {
	return "#?RADIANCE\n# made by the test\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2.0\n" + p_extra + "\n-Y " + std::to_string(p_height) + " +X " +
			std::to_string(p_width) + "\n";
}

std::vector<uint8_t> bytes_of(const std::string &p_text) {
	return std::vector<uint8_t>(p_text.begin(), p_text.end());
}

// Flat: 4 bytes a pixel.
std::vector<uint8_t> encode_flat(const std::vector<Rgbe> &p_pixels, int p_width, int p_height) {
	std::vector<uint8_t> out = bytes_of(header(p_width, p_height));
	for (const Rgbe &p : p_pixels) {
		out.insert(out.end(), p.begin(), p.end());
	}
	return out;
}

// New-style runs: repeats of 3 or more as a run (count + 128, byte), the rest as literals.
std::vector<uint8_t> encode_rle(const std::vector<Rgbe> &p_pixels, int p_width, int p_height) {
	std::vector<uint8_t> out = bytes_of(header(p_width, p_height));
	for (int y = 0; y < p_height; ++y) {
		out.insert(out.end(), { 2, 2, uint8_t(p_width >> 8), uint8_t(p_width & 0xFF) });
		for (int c = 0; c < 4; ++c) {
			const auto at = [&](int p_x) { return p_pixels[size_t(y) * p_width + p_x][c]; };
			int x = 0;
			while (x < p_width) {
				int run = 1;
				while (x + run < p_width && run < 127 && at(x + run) == at(x)) {
					++run;
				}
				if (run >= 3) {
					out.insert(out.end(), { uint8_t(128 + run), at(x) });
					x += run;
					continue;
				}
				int literal = 1;
				while (x + literal < p_width && literal < 128 && !(x + literal + 2 < p_width && at(x + literal) == at(x + literal + 1) && at(x + literal) == at(x + literal + 2))) {
					++literal;
				}
				out.push_back(uint8_t(literal));
				for (int k = 0; k < literal; ++k) {
					out.push_back(at(x + k));
				}
				x += literal;
			}
		}
	}
	return out;
}

// r * 2^(e - 136), 0 when e is 0: in double, exact, then a float.
cv::Mat expected_rgb(const std::vector<Rgbe> &p_pixels, int p_width, int p_height) {
	cv::Mat rgb(p_height, p_width, CV_32FC3);
	for (int i = 0; i < p_width * p_height; ++i) {
		const Rgbe &p = p_pixels[size_t(i)];
		for (int c = 0; c < 3; ++c) {
			rgb.ptr<float>()[3 * i + c] = p[3] == 0 ? 0.0f : float(std::ldexp(double(p[c]), p[3] - 136));
		}
	}
	return rgb;
}

double max_difference(const cv::Mat &p_a, const cv::Mat &p_b) {
	REQUIRE(p_a.type() == p_b.type());
	REQUIRE(p_a.size() == p_b.size());
	return cv::norm(p_a, p_b, cv::NORM_INF);
}

std::string decode_error(const std::vector<uint8_t> &p_bytes) {
	cv::Mat out;
	const std::string error = radiance_hdr_decode(p_bytes.data(), p_bytes.size(), &out);
	CHECK(out.empty()); // nothing is given back on failure
	return error;
}

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

} // namespace

TEST_CASE("radiance hdr: the real panoramas decode bit for bit as cv::imread reads them") {
	for (const char *name : { "lebombo_1k.hdr", "studio_small_03_1k.hdr" }) {
		const std::string path = std::string(ROOMPROBE_SHARED_DATA) + "/hdri/" + name;
		CAPTURE(path);
		if (!std::filesystem::is_regular_file(path)) {
			MESSAGE("skipped: " << path << " is missing (../shared/data/hdri)");
			continue;
		}
		cv::Mat ours;
		REQUIRE(radiance_hdr_read(path, &ours) == "");
		REQUIRE(ours.type() == CV_32FC3);
		cv::Mat theirs;
		cv::cvtColor(cv::imread(path, cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR), theirs, cv::COLOR_BGR2RGB);
		CHECK(ours.cols == 1024);
		CHECK(ours.rows == 512);
		CHECK(max_difference(ours, theirs) == 0.0);
	}
}

TEST_CASE("radiance hdr: flat, new-style and old-style run-length scanlines decode to r * 2^(e - 136)") {
	const int width = 20, height = 3;
	const std::vector<Rgbe> pixels = test_pixels(width, height);
	const cv::Mat expected = expected_rgb(pixels, width, height);
	CHECK(expected.at<cv::Vec3f>(0, 0) == cv::Vec3f(1.0f, 0.5f, 1.9921875f));
	cv::Mat out;
	const std::vector<uint8_t> flat = encode_flat(pixels, width, height);
	REQUIRE(radiance_hdr_decode(flat.data(), flat.size(), &out) == "");
	CHECK(max_difference(out, expected) == 0.0);
	const std::vector<uint8_t> rle = encode_rle(pixels, width, height);
	REQUIRE(rle.size() < flat.size()); // runs were made ...
	REQUIRE(std::count_if(rle.begin() + long(header(width, height).size()), rle.end(), [](uint8_t b) { return b > 128; }) > 0);
	REQUIRE(radiance_hdr_decode(rle.data(), rle.size(), &out) == "");
	CHECK(max_difference(out, expected) == 0.0);
	// Width 4: too narrow for new-style runs, so (2, 2, ...) is a pixel.
	const std::vector<Rgbe> narrow = { { 2, 2, 0, 4 }, { 255, 0, 0, 128 }, { 1, 2, 3, 140 }, { 0, 0, 0, 0 } };
	const std::vector<uint8_t> narrow_bytes = encode_flat(narrow, 4, 1);
	REQUIRE(radiance_hdr_decode(narrow_bytes.data(), narrow_bytes.size(), &out) == "");
	CHECK(max_difference(out, expected_rgb(narrow, 4, 1)) == 0.0);
	// Old-style: (1, 1, 1, 3) repeats the pixel before it 3 times, a second marker right after it
	// 2 << 8 times; after a pixel, (1, 1, 1, 1) repeats it once. No header lines but the empty one.
	std::vector<uint8_t> old_style = bytes_of("#?RGBE\n\n-Y 1 +X 518\n");
	old_style.insert(old_style.end(), { 128, 64, 32, 130, 1, 1, 1, 3, 1, 1, 1, 2, 200, 100, 50, 120, 1, 1, 1, 1 });
	REQUIRE(radiance_hdr_decode(old_style.data(), old_style.size(), &out) == "");
	std::vector<Rgbe> old_expected(518, Rgbe { 128, 64, 32, 130 });
	old_expected[516] = old_expected[517] = { 200, 100, 50, 120 };
	CHECK(max_difference(out, expected_rgb(old_expected, 518, 1)) == 0.0);
}

TEST_CASE("radiance hdr: truncated and malformed files are refused with what is wrong") {
	const int width = 20, height = 3;
	const std::vector<uint8_t> rle = encode_rle(test_pixels(width, height), width, height);
	const std::vector<uint8_t> flat = encode_flat(test_pixels(width, height), width, height);
	// Every prefix of either file: refused, never read past its end (the sanitizer builds check).
	for (const std::vector<uint8_t> *whole : { &rle, &flat }) {
		for (size_t size = 0; size < whole->size(); ++size) {
			CAPTURE(size);
			const std::string error = decode_error(std::vector<uint8_t>(whole->begin(), whole->begin() + long(size)));
			CHECK(error.find("the data: ") == 0);
			CHECK((contains(error, "truncated") || contains(error, "not a Radiance .hdr")));
		}
	}
	CHECK(contains(decode_error(std::vector<uint8_t>(rle.begin(), rle.end() - 5)), "truncated: the data ends inside scanline 3 of 3"));
	CHECK(contains(decode_error(bytes_of("P6\n20 3\n")), "not a Radiance .hdr"));
	CHECK(contains(decode_error(bytes_of(header(20, 3, "FORMAT=32-bit_rle_xyze\n"))), "XYZE colour is not read"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n0000")), "FORMAT=32-bit_rle_xyze"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\nFORMAT=rgb\n\n-Y 1 +X 1\n0000")), "FORMAT='rgb' is not 32-bit_rle_rgbe"));
	// The resolution line.
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n")), "no resolution line"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n+Y 3 +X 20\n")), "the resolution line '+Y 3 +X 20' is in an orientation not read"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n+X 20 -Y 3\n")), "orientation not read"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y three +X 20\n")), "the resolution line '-Y three +X 20' is not -Y HEIGHT +X WIDTH"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y 3 -Y 20\n")), "is not -Y HEIGHT +X WIDTH"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y 0 +X 20\n")), "the image has no pixels (20x0)"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y 40000 +X 20\n")), "more than RoomProbe reads"));
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y 99999999999999999999 +X 20\n")), "is not -Y HEIGHT +X WIDTH"));
	// A large image claimed by a few bytes: refused for its missing scanlines, before the 3 GB are allocated.
	CHECK(contains(decode_error(bytes_of("#?RADIANCE\n\n-Y 16384 +X 16384\n\x02\x02\x40")), "truncated: the data ends inside scanline 1 of 16384"));
	// Runs that would overflow the scanline: new-style run and literal, old-style run.
	std::vector<uint8_t> run = bytes_of(header(8, 1));
	run.insert(run.end(), { 2, 2, 0, 8, 128 + 9, 7 });
	CHECK(contains(decode_error(run), "scanline 1 of 1, channel R, pixel 1: a run of 9 overflows the 8-pixel scanline"));
	run.resize(run.size() - 2);
	run.insert(run.end(), { 128 + 4, 7, 5, 1, 2, 3, 4, 5 });
	CHECK(contains(decode_error(run), "channel R, pixel 5: 5 literal bytes overflow the 8-pixel scanline"));
	run.resize(run.size() - 6);
	run.insert(run.end(), { 0, 1 });
	CHECK(contains(decode_error(run), "a run of length 0"));
	std::vector<uint8_t> wrong_width = bytes_of(header(8, 1));
	wrong_width.insert(wrong_width.end(), { 2, 2, 0, 9 });
	CHECK(contains(decode_error(wrong_width), "scanline 1 of 1 says it is 9 pixels wide, the image 8"));
	std::vector<uint8_t> old_run = bytes_of(header(4, 1));
	old_run.insert(old_run.end(), { 128, 1, 1, 130, 1, 1, 1, 4 });
	CHECK(contains(decode_error(old_run), "pixel 2: an old-style run of 4 overflows the 4-pixel scanline"));
	std::vector<uint8_t> old_first = bytes_of(header(4, 1));
	old_first.insert(old_first.end(), { 1, 1, 1, 2 });
	CHECK(contains(decode_error(old_first), "begins with an old-style run"));
	cv::Mat out;
	CHECK(radiance_hdr_decode(nullptr, 0, &out) == "the data: not a Radiance .hdr (it does not begin with #?RADIANCE or #?RGBE)");
	CHECK(radiance_hdr_read("/nonexistent/sky.hdr", &out) == "/nonexistent/sky.hdr: missing");
}

TEST_CASE("radiance hdr: load_panorama tells .hdr, EXR, PNG and other files by their bytes, not their names") {
	const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("roomprobe_radiance_hdr_" + std::to_string(::getpid()));
	std::filesystem::create_directories(dir);
	const int width = 20, height = 3;
	const std::vector<Rgbe> pixels = test_pixels(width, height);
	const cv::Mat expected = expected_rgb(pixels, width, height);
	const auto write = [&](const std::string &p_name, const std::vector<uint8_t> &p_bytes) {
		std::ofstream((dir / p_name).string(), std::ios::binary).write(reinterpret_cast<const char *>(p_bytes.data()), long(p_bytes.size()));
		return (dir / p_name).string();
	};
	const auto same = [&](const synth::PanoramaLoadResult &p_result, const cv::Mat &p_rgb) {
		REQUIRE(p_result.ok);
		REQUIRE(p_result.panorama->width == p_rgb.cols);
		REQUIRE(p_result.panorama->height == p_rgb.rows);
		const cv::Mat loaded(p_rgb.rows, p_rgb.cols, CV_32FC3, const_cast<float *>(p_result.panorama->rgb.data()));
		return max_difference(loaded, p_rgb);
	};
	CHECK(same(synth::load_panorama(write("sky.png", encode_rle(pixels, width, height))), expected) == 0.0); // an .hdr named .png
	REQUIRE(recording_io::write_exr_rgb((dir / "sky.exr").string(), expected, true) == "");
	CHECK(same(synth::load_panorama((dir / "sky.exr").string()), expected) == 0.0);
	// An 8-bit PNG (B, G, R): R, G, B linear, sRGB undone with gamma 2.2.
	const cv::Mat bgr(2, 3, CV_8UC3, cv::Scalar(51, 102, 255));
	REQUIRE(png_write((dir / "ldr.hdr").string(), bgr) == "");
	const cv::Mat linear(2, 3, CV_32FC3, cv::Scalar(1.0, std::pow(0.4, 2.2), std::pow(0.2, 2.2)));
	CHECK(same(synth::load_panorama((dir / "ldr.hdr").string()), linear) < 1e-6);
	const std::string text = write("notes.txt", bytes_of("hello"));
	CHECK(synth::load_panorama(text).error == text + ": not a Radiance .hdr, OpenEXR, PNG or JPEG file, so the panorama cannot be read");
	const std::string broken = write("broken.hdr", bytes_of("#?RADIANCE\n\n+Y 3 +X 20\n"));
	CHECK(contains(synth::load_panorama(broken).error, broken + ": the resolution line '+Y 3 +X 20' is in an orientation not read"));
	CHECK(contains(synth::load_panorama(broken).error, "so the panorama cannot be read"));
	std::filesystem::remove_all(dir);
}
