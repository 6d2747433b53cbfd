// eval/metrics.h: PSNR and SSIM between cubemaps.

#include <io/opencv.h>

#include "envmap/export.h"
#include "eval/metrics.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace roomprobe;

namespace {

float srgb8_to_linear(int p_v) {
	const float v = float(p_v) / 255.0f;
	return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

} // namespace

TEST_CASE("eval: metrics of identical cubemaps") {
	Cubemap a = make_cubemap(32, cv::Vec3f(0.2f, 0.4f, 0.6f));
	for (int f = 0; f < 6; f++) {
		cv::randu(a.faces[f], 0.0f, 1.0f);
	}
	const CubemapMetrics m = compare_cubemaps(a, a);
	REQUIRE(m.ok);
	CHECK(m.psnr_db == PSNR_CAP_DB); // capped, not +inf
	CHECK(m.psnr_linear_db == PSNR_CAP_DB);
	CHECK(m.ssim == doctest::Approx(1.0).epsilon(1e-9));
	CHECK(m.ssim_linear == doctest::Approx(1.0).epsilon(1e-9));
	CHECK_FALSE(compare_cubemaps(a, make_cubemap(16)).ok);
}

TEST_CASE("eval: PSNR of a known noise level") {
	// Ground truth: 8-bit sRGB value 128 everywhere; estimate: 128 + N(0, 5^2), rounded, decoded
	// to linear so that the tone map gives back exactly those 8-bit values.
	// Expected: 10 log10(255^2 / (25 + 1/12)) = 34.14 dB.
	const int size = 64;
	Cubemap truth = make_cubemap(size, cv::Vec3f(srgb8_to_linear(128), srgb8_to_linear(128), srgb8_to_linear(128)));
	Cubemap noisy = make_cubemap(size);
	std::mt19937 random(7);
	std::normal_distribution<double> noise(0.0, 5.0);
	double squared = 0.0;
	size_t count = 0;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < size; y++) {
			for (int x = 0; x < size; x++) {
				for (int c = 0; c < 3; c++) {
					const int v = int(std::lround(128.0 + noise(random)));
					noisy.faces[f].at<cv::Vec3f>(y, x)[c] = srgb8_to_linear(v);
					REQUIRE(tone_map_srgb8(srgb8_to_linear(v)) == v);
					squared += double(v - 128) * (v - 128);
					count++;
				}
			}
		}
	}
	const CubemapMetrics m = compare_cubemaps(noisy, truth);
	REQUIRE(m.ok);
	CHECK(m.psnr_db == doctest::Approx(10.0 * std::log10(255.0 * 255.0 / (squared / double(count)))).epsilon(1e-9));
	CHECK(std::abs(m.psnr_db - 10.0 * std::log10(255.0 * 255.0 / (25.0 + 1.0 / 12.0))) < 0.1);
	CHECK(m.ssim < 0.9);
	CHECK(m.ssim > 0.0);
}

TEST_CASE("eval: SSIM falls with structure loss") {
	Cubemap truth = make_cubemap(32);
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < 32; y++) {
			for (int x = 0; x < 32; x++) {
				const float v = ((x / 4 + y / 4) % 2) ? 0.8f : 0.1f;
				truth.faces[f].at<cv::Vec3f>(y, x) = cv::Vec3f(v, v, v);
			}
		}
	}
	const Cubemap flat = make_cubemap(32, cv::Vec3f(0.45f, 0.45f, 0.45f));
	const CubemapMetrics m = compare_cubemaps(flat, truth);
	REQUIRE(m.ok);
	CHECK(m.ssim < 0.1);
	CHECK(m.psnr_db < 20.0);
}

TEST_CASE("eval: HDR PSNR on the mu-law with a fixed peak, and the worst 5 % of directions") {
	const int size = 20; // 6 x 400 = 2400 pixels: 120 are the worst 5 %
	// Truth: a lamp at 25 (above white) everywhere; the estimate clipped at 1, as an 8-bit capture.
	const Cubemap lamp = make_cubemap(size, cv::Vec3f(25.0f, 25.0f, 25.0f));
	const Cubemap clipped = make_cubemap(size, cv::Vec3f(1.0f, 1.0f, 1.0f));
	const auto mu = [](double p_x) { return std::log1p(MU_LAW * std::min(p_x, HDR_PEAK) / HDR_PEAK) / std::log1p(MU_LAW); };
	const CubemapMetrics m = compare_cubemaps(clipped, lamp);
	REQUIRE(m.ok);
	const double d = mu(25.0) - mu(1.0);
	CHECK(m.psnr_mu_db == doctest::Approx(-10.0 * std::log10(d * d)).epsilon(1e-9));
	CHECK(m.psnr_db == PSNR_CAP_DB); // tone-mapped, both are white: the HDR metric is what tells them apart
	// The peak is fixed: a brighter truth does not flatter an estimate with the same error.
	const CubemapMetrics dim = compare_cubemaps(make_cubemap(size, cv::Vec3f(0.6f, 0.6f, 0.6f)), make_cubemap(size, cv::Vec3f(0.5f, 0.5f, 0.5f)));
	const double d_dim = mu(double(0.6f)) - mu(double(0.5f)); // the faces hold floats
	CHECK(dim.psnr_mu_db == doctest::Approx(-10.0 * std::log10(d_dim * d_dim)).epsilon(1e-9));

	// 120 pixels off by 40 tone-mapped levels, the rest exact: the worst 5 % is exactly those.
	Cubemap truth = make_cubemap(size, cv::Vec3f(srgb8_to_linear(100), srgb8_to_linear(100), srgb8_to_linear(100)));
	Cubemap estimate = truth;
	for (int f = 0; f < 6; f++) {
		estimate.faces[f] = truth.faces[f].clone();
	}
	for (int i = 0; i < 120; i++) {
		estimate.faces[i % 6].at<cv::Vec3f>(i / 6, 0) = cv::Vec3f(srgb8_to_linear(140), srgb8_to_linear(140), srgb8_to_linear(140));
	}
	const CubemapMetrics w = compare_cubemaps(estimate, truth);
	CHECK(w.psnr_worst5_db == doctest::Approx(10.0 * std::log10(255.0 * 255.0 / 1600.0)).epsilon(1e-9));
	CHECK(w.psnr_db == doctest::Approx(10.0 * std::log10(255.0 * 255.0 / (1600.0 * 120.0 / 2400.0))).epsilon(1e-9));
}
