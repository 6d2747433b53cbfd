// GGX prefiltering of the probe's map for rough materials (envmap/ggx_prefilter.h): the importance-
// sampled chain against a brute-force convolution of every source texel, at three roughnesses, on
// a map with a small bright light and smooth walls (the hard case: a peak the lobe must spread).

#include "envmap/ggx_prefilter.h"
#include "types/cubemap_layout.h"

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
	// The default chain: faces 64 down to 4 (five levels), Godot's roughness per level.
	CHECK(ggx_default_levels(64) == 5);
	CHECK(ggx_default_levels(256) == 7);
	CHECK(ggx_default_levels(4) == 1);
	CHECK(ggx_level_roughness(0, 5) == 0.0);
	CHECK(ggx_level_roughness(2, 5) == doctest::Approx(0.25));
	CHECK(ggx_level_roughness(4, 5) == 1.0);
	for (int samples : { 256, 1024 }) {
		GgxPrefilterOptions options;
		options.samples = samples;
		const GgxFilter filter(64, options);
		REQUIRE(filter.is_valid());
		const std::vector<Cubemap> chain = filter.apply(source);
		REQUIRE(chain.size() == 5);
		CHECK(chain[0].size == 64);
		CHECK(chain[4].size == 4);
		MESSAGE(samples << " samples: " << filter.tap_count() << " taps, " << filter.memory_bytes() / 1024 << " KiB");
		for (int level : { 2, 3, 4 }) {
			const double roughness = ggx_level_roughness(level, 5);
			const Cubemap reference = ggx_reference(source, roughness, chain[size_t(level)].size);
			const double error = relative_rms(chain[size_t(level)], reference);
			CAPTURE(samples);
			CAPTURE(roughness);
			MESSAGE(samples << " samples, roughness " << roughness << " (" << chain[size_t(level)].size << " px faces): relative RMS against brute force " << 100.0 * error << " %");
			// The sampled estimate's noise on the light's peak (real rooms have no such peak):
			// 1.5 to 5.4 % at 1024 samples (the finest level read is k - 1), up to 8 % at 256, the
			// probe worker's default.
			CHECK(error < (samples >= 1024 ? 0.06 : 0.10));
		}
		// The same filter again gives the same chain; a source of another size is refused.
		const std::vector<Cubemap> again = filter.apply(source);
		CHECK(cv::norm(again[3].faces[2], chain[3].faces[2], cv::NORM_INF) == 0.0);
		CHECK(filter.apply(test_map(32)).empty());
	}
	GgxPrefilterOptions options;
	options.levels = 5;
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

TEST_CASE("ggx prefilter: one filter per size for the whole process, small ones at once, larger ones in the background") {
	const std::shared_ptr<const GgxFilter> small = shared_ggx_filter(32);
	REQUIRE(small != nullptr); // up to 64^2: built by the call
	CHECK(small->face_size() == 32);
	CHECK(small->level_count() == ggx_default_levels(32));
	CHECK(shared_ggx_filter(32) == small);
	CHECK(shared_ggx_filter(0) == nullptr);
	// 128^2: the first call may return before it is built; waiting gives it, and then every call.
	const std::shared_ptr<const GgxFilter> large = shared_ggx_filter(128, true);
	REQUIRE(large != nullptr);
	CHECK(large->face_size() == 128);
	CHECK(shared_ggx_filter(128) == large);
}

TEST_CASE("ggx prefilter after a change of some faces: every texel as a whole filtering gives it, and the untouched faces' fine levels kept") {
	const std::shared_ptr<const GgxFilter> filter = shared_ggx_filter(64);
	REQUIRE(filter != nullptr);
	const Cubemap before = test_map(64);
	const std::vector<Cubemap> old_chain = filter->apply(before);
	// Face 2 (+y) brightened: its colours and nothing else change.
	Cubemap after = clone_cubemap(before);
	after.faces[2] += cv::Scalar(0.5, 0.25, 0.1);
	const uint8_t changed = cubemap_changed_faces(before, after);
	CHECK(changed == (1u << 2));
	CHECK(cubemap_changed_faces(after, after) == 0);
	CHECK(cubemap_changed_faces(after, test_map(32)) == 0x3F);
	uint8_t out_changed = 0;
	const std::vector<Cubemap> partial = filter->apply(after, old_chain, changed, &out_changed);
	const std::vector<Cubemap> whole = filter->apply(after);
	REQUIRE(partial.size() == whole.size());
	for (size_t l = 0; l < whole.size(); l++) {
		CAPTURE(l);
		REQUIRE(partial[l].size == whole[l].size);
		for (int f = 0; f < 6; f++) {
			CHECK(cv::norm(partial[l].faces[size_t(f)], whole[l].faces[size_t(f)], cv::NORM_INF) == 0.0); // the same sums in the same order
		}
	}
	// The opposite face (-y) reads nothing of +y at the sharp levels, but the roughest read every face.
	CHECK((out_changed & (1u << 2)) != 0);
	CHECK((out_changed & (1u << 3)) != 0);
	const int sharp = 1; // level 1: alpha 0.0016 at 6 levels
	CHECK(cv::norm(partial[size_t(sharp)].faces[3], old_chain[size_t(sharp)].faces[3], cv::NORM_INF) == 0.0);
	// Nothing changed: the previous chain comes back, nothing computed.
	const std::vector<Cubemap> same = filter->apply(after, whole, 0, &out_changed);
	CHECK(out_changed == 0);
	CHECK(cv::norm(same.back().faces[0], whole.back().faces[0], cv::NORM_INF) == 0.0);
	// A previous chain of another size is not used.
	const std::vector<Cubemap> fresh = filter->apply(after, shared_ggx_filter(32)->apply(test_map(32)), changed, &out_changed);
	CHECK(out_changed == 0x3F);
	CHECK(cv::norm(fresh[1].faces[0], whole[1].faces[0], cv::NORM_INF) == 0.0);
}
