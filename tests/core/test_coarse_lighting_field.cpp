// The lighting change as a gain field (issue #42, coarse/lighting_field.h): a known field is
// found from noisy pairs with outliers; with the field off, or with pairs that agree on one
// gain, the change is one gain; fields compose and undo as gains do; applied per texel point.

#include "coarse/lighting.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace roomprobe;

namespace {

// Pairs on a 4 x 2.5 x 3 m room's surfaces with new = g_c * exp(slope . x) * old, 2 % noise,
// and p_outliers of them replaced by unrelated values (a person walking through the view).
std::vector<LightingSample> field_pairs(const cv::Vec3f &p_gain, const cv::Vec3f &p_slope, double p_outliers, uint32_t p_seed) {
	std::mt19937 random(p_seed);
	std::uniform_real_distribution<float> unit(0.0f, 1.0f);
	std::normal_distribution<float> noise(0.0f, 0.02f);
	std::vector<LightingSample> samples;
	for (int i = 0; i < 4000; i++) {
		const cv::Vec3f position(4.0f * unit(random), 2.5f * unit(random), 3.0f * unit(random));
		const cv::Vec3f old_value(0.1f + 0.3f * unit(random), 0.1f + 0.3f * unit(random), 0.1f + 0.3f * unit(random));
		const float field = std::exp(p_slope.dot(position));
		cv::Vec3f new_value;
		for (int c = 0; c < 3; c++) {
			new_value[c] = old_value[c] * p_gain[c] * field * (1.0f + noise(random));
		}
		if (unit(random) < p_outliers) {
			new_value = cv::Vec3f(0.05f + 0.8f * unit(random), 0.05f + 0.8f * unit(random), 0.05f + 0.8f * unit(random));
		}
		samples.push_back({ old_value, new_value, position });
	}
	return samples;
}

LightingOptions field_options(double p_prior_per_m) {
	LightingOptions options;
	options.saturated_threshold = 10.0f; // linear values, none clipped
	options.field_prior_per_m = p_prior_per_m;
	return options;
}

} // namespace

TEST_CASE("lighting field: a light brightening one side of the room is found from noisy pairs with 20 % outliers") {
	// A light switched on low in the room at x = 0: 1.8 x brighter there, about 1.1 x at the far wall.
	const cv::Vec3f gain(1.8f, 1.7f, 1.5f), slope(-0.12f, -0.08f, 0.0f);
	const LightingChange change = estimate_lighting_change(field_pairs(gain, slope, 0.2, 7), field_options(0.3));
	REQUIRE(change.valid);
	REQUIRE(change.has_field());
	// The prior pulls the slope towards 0 by sigma^2 / prior^2 against the pairs' spread: with
	// 3200 inliers over metres, well under 0.01 per metre.
	for (int k = 0; k < 3; k++) {
		CHECK(std::abs(change.log_slope[k] - slope[k]) < 0.01f);
	}
	for (const cv::Vec3f &at : { cv::Vec3f(0.0f, 0.0f, 0.0f), cv::Vec3f(4.0f, 2.5f, 3.0f), cv::Vec3f(2.0f, 1.0f, 1.5f) }) {
		const cv::Vec3f found = change.gain_at(glm::vec3(at[0], at[1], at[2]));
		for (int c = 0; c < 3; c++) {
			const float truth = gain[c] * std::exp(slope.dot(at));
			CHECK(std::abs(found[c] / truth - 1.0f) < 0.02f);
		}
	}
}

TEST_CASE("lighting field: off, or pairs that agree on one gain, give one gain") {
	const std::vector<LightingSample> uniform = field_pairs(cv::Vec3f(1.3f, 1.3f, 1.2f), cv::Vec3f(0.0f, 0.0f, 0.0f), 0.1, 11);
	const LightingChange off = estimate_lighting_change(uniform, field_options(0.0));
	REQUIRE(off.valid);
	CHECK_FALSE(off.has_field());
	const LightingChange on = estimate_lighting_change(uniform, field_options(0.3));
	REQUIRE(on.valid);
	CHECK(cv::norm(on.log_slope) < 0.005);
	for (int c = 0; c < 3; c++) {
		CHECK(std::abs(on.gain_at(glm::vec3(2.0f, 1.2f, 1.5f))[c] - off.gain[c]) < 0.01f * off.gain[c]);
	}
	// Pairs without positions (an atlas without geometry): one gain, whatever the option.
	std::vector<LightingSample> unplaced = uniform;
	for (LightingSample &sample : unplaced) {
		sample.position = cv::Vec3f(NAN, NAN, NAN);
	}
	CHECK_FALSE(estimate_lighting_change(unplaced, field_options(0.3)).has_field());
}

TEST_CASE("lighting field: fields compose and undo as gains do, and apply at each point") {
	LightingChange first, then;
	first.valid = then.valid = true;
	first.gain = cv::Vec3f(1.5f, 1.4f, 1.3f);
	first.log_slope = cv::Vec3f(-0.1f, 0.05f, 0.0f);
	then.gain = cv::Vec3f(0.8f, 0.9f, 1.0f);
	then.log_slope = cv::Vec3f(0.02f, 0.0f, -0.03f);
	const LightingChange both = compose_lighting(then, first);
	const glm::vec3 at(1.0f, 2.0f, 3.0f);
	const cv::Vec3f value(0.2f, 0.3f, 0.4f);
	const cv::Vec3f twice = then.apply(first.apply(value, at), at);
	const cv::Vec3f once = both.apply(value, at);
	for (int c = 0; c < 3; c++) {
		CHECK(once[c] == doctest::Approx(twice[c]).epsilon(1e-5));
	}
	const LightingChange since = lighting_since(both, first);
	const cv::Vec3f back = since.apply(first.apply(value, at), at);
	for (int c = 0; c < 3; c++) {
		CHECK(back[c] == doctest::Approx(once[c]).epsilon(1e-5));
	}
	// Applied to a texture: each texel by its own point.
	CoarseTexture texture;
	texture.color = cv::Mat(1, 2, CV_32FC3, cv::Scalar(0.25, 0.25, 0.25));
	texture.observed = cv::Mat(1, 2, CV_8UC1, cv::Scalar(255));
	texture.updated = cv::Mat(1, 2, CV_8UC1, cv::Scalar(0));
	const std::vector<glm::dvec3> points = { glm::dvec3(0.0, 0.0, 0.0), glm::dvec3(4.0, 0.0, 0.0) };
	apply_lighting_change(&texture, first, &points);
	CHECK(texture.color.at<cv::Vec3f>(0, 0)[0] == doctest::Approx(0.25f * 1.5f));
	CHECK(texture.color.at<cv::Vec3f>(0, 1)[0] == doctest::Approx(0.25f * 1.5f * std::exp(-0.4f)));
}
