// GGX prefiltering of the probe's map for rough materials (envmap/ggx_prefilter.h): the importance-
// sampled chain against a brute-force convolution of every source texel, at three roughnesses, on
// a map with a small bright light and smooth walls (the hard case: a peak the lobe must spread).

#include "envmap/ggx_prefilter.h"
#include "recording/cubemap_layout.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>

using namespace roomprobe;

namespace {

Cubemap test_map(int p_size) {
	Cubemap map = make_cubemap(p_size);
	const glm::dvec3 light = glm::normalize(glm::dvec3(0.3, 1.0, 0.2));
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < p_size; y++) {
			for (int x = 0; x < p_size; x++) {
				const glm::dvec3 d = cubemap_direction(f, x, y, p_size);
				// Walls: a gradient and a stripe; a light of radiance 20 about 8 degrees across.
				double r = 0.3 + 0.2 * d.y + 0.1 * std::sin(6.0 * d.x), g = 0.25 + 0.1 * d.z, b = 0.2 + 0.15 * d.x * d.x;
				if (glm::dot(d, light) > std::cos(8.0 * 3.14159265358979 / 180.0)) {
					r = g = b = 20.0;
				}
				map.faces[size_t(f)].at<cv::Vec3f>(y, x) = cv::Vec3f(float(r), float(g), float(b));
			}
		}
	}
	return map;
}

double relative_rms(const Cubemap &p_a, const Cubemap &p_b) {
	double se = 0.0, sum = 0.0;
	size_t n = 0;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < p_a.size; y++) {
			for (int x = 0; x < p_a.size; x++) {
				const cv::Vec3f a = p_a.faces[size_t(f)].at<cv::Vec3f>(y, x), b = p_b.faces[size_t(f)].at<cv::Vec3f>(y, x);
				for (int c = 0; c < 3; c++) {
					se += double(a[c] - b[c]) * double(a[c] - b[c]);
					sum += b[c];
					n++;
				}
			}
		}
	}
	return std::sqrt(se / double(n)) / (sum / double(n));
}

} // namespace

TEST_CASE("ggx prefilter: the sampled chain matches a brute-force GGX convolution at three roughnesses") {
	const Cubemap source = test_map(64);
	GgxPrefilterOptions options;
	options.levels = 6;
	options.samples = 1024;
	const std::vector<Cubemap> chain = prefilter_ggx(source, options);
	REQUIRE(chain.size() == 6);
	CHECK(chain[0].size == 64);
	CHECK(chain[5].size == 2);
	CHECK(ggx_level_roughness(0, 6) == 0.0);
	CHECK(ggx_level_roughness(5, 6) == 1.0);
	for (int level : { 2, 3, 5 }) {
		const double roughness = ggx_level_roughness(level, 6);
		const Cubemap reference = ggx_reference(source, roughness, chain[size_t(level)].size);
		const double error = relative_rms(chain[size_t(level)], reference);
		CAPTURE(roughness);
		MESSAGE("roughness " << roughness << " (" << chain[size_t(level)].size << " px faces): relative RMS against brute force " << 100.0 * error << " %");
		// 1024 samples a texel: the sampled estimate's noise on the light's peak is a few %.
		CHECK(error < 0.05);
	}
	// Energy: a constant map stays constant at every level.
	const std::vector<Cubemap> flat = prefilter_ggx(make_cubemap(16, cv::Vec3f(0.5f, 0.5f, 0.5f)), options);
	for (const Cubemap &level : flat) {
		double lo = 0.0, hi = 0.0;
		for (const cv::Mat &face : level.faces) {
			cv::minMaxLoc(face.reshape(1), &lo, &hi);
			CHECK(lo == doctest::Approx(0.5).epsilon(1e-4));
			CHECK(hi == doctest::Approx(0.5).epsilon(1e-4));
		}
	}
	CHECK(prefilter_ggx(Cubemap(), options).empty());
}
