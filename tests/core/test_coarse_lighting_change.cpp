// Large-scale lighting change (paper §4.6): the paper's additive Δ with its validity function,
// the robust per-channel gain, and applying the change to the texels not updated this frame.

#include <io/opencv.h>

#include "coarse/coarse_texture.h"
#include "coarse/lighting.h"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace roomprobe;

namespace {

CoarseTexture blank_texture(int p_width, int p_height) {
	CoarseTexture texture;
	texture.color = cv::Mat(p_height, p_width, CV_32FC3, cv::Scalar::all(0.0));
	texture.observed = cv::Mat(p_height, p_width, CV_8UC1, cv::Scalar(0));
	texture.quality = cv::Mat(p_height, p_width, CV_32FC1, cv::Scalar(0.0));
	texture.updated = cv::Mat(p_height, p_width, CV_8UC1, cv::Scalar(0));
	return texture;
}

struct Scene {
	CoarseTexture before;
	cv::Mat new_color;
	cv::Mat visible;
};

// A 200 x 100 atlas, all observed and visible; new = gain · old (+ a little noise), except a
// "person" rectangle covering 20 % of the texels with unrelated colours, and a few saturated and
// black texels.
Scene gain_scene(const cv::Vec3f &p_gain, bool p_person, std::mt19937 *r_rng) {
	const int width = 200, height = 100;
	Scene scene{ blank_texture(width, height), cv::Mat(height, width, CV_32FC3), cv::Mat(height, width, CV_8UC1, cv::Scalar(255)) };
	scene.before.observed.setTo(255);
	std::uniform_real_distribution<float> albedo(0.08f, 0.7f);
	std::uniform_real_distribution<float> clothing(0.02f, 0.95f);
	std::normal_distribution<float> noise(0.0f, 0.002f);
	std::bernoulli_distribution rare(0.03);
	const cv::Rect person(40, 0, 40, 100); // 40 * 100 / (200 * 100) = 20 %.
	for (int y = 0; y < height; y++) {
		for (int x = 0; x < width; x++) {
			cv::Vec3f old_value(albedo(*r_rng), albedo(*r_rng), albedo(*r_rng));
			cv::Vec3f new_value;
			for (int c = 0; c < 3; c++) {
				new_value[c] = p_gain[c] * old_value[c] + noise(*r_rng);
			}
			if (p_person && person.contains(cv::Point(x, y))) {
				new_value = cv::Vec3f(clothing(*r_rng), clothing(*r_rng), clothing(*r_rng));
			} else if (rare(*r_rng)) {
				new_value = cv::Vec3f(1.0f, 1.0f, 1.0f); // Saturated: would pull a mean up.
			} else if (rare(*r_rng)) {
				old_value = cv::Vec3f(0.0f, 0.0f, 0.0f); // Black before: would pull a mean up.
			}
			scene.before.color.at<cv::Vec3f>(y, x) = old_value;
			scene.new_color.at<cv::Vec3f>(y, x) = new_value;
		}
	}
	return scene;
}

double max_relative_error(const cv::Vec3f &p_got, const cv::Vec3f &p_want) {
	double error = 0.0;
	for (int c = 0; c < 3; c++) {
		error = std::max(error, std::abs(static_cast<double>(p_got[c]) - p_want[c]) / std::abs(static_cast<double>(p_want[c])));
	}
	return error;
}

} // namespace

TEST_CASE("lighting: the robust gain recovers a known gain despite 20 % outliers; the paper's mean is biased") {
	std::mt19937 rng(2024);
	const cv::Vec3f gain(1.35f, 1.2f, 0.85f);
	const Scene clean = gain_scene(gain, false, &rng);
	const Scene people = gain_scene(gain, true, &rng);

	LightingOptions robust_options;
	robust_options.model = LightingModel::GAIN_ROBUST;
	LightingOptions paper_options;
	paper_options.model = LightingModel::ADDITIVE_PAPER;

	const LightingChange robust = estimate_lighting_change(people.before, people.new_color, people.visible, robust_options);
	REQUIRE(robust.valid);
	CHECK(robust.model == LightingModel::GAIN_ROBUST);
	const double gain_error = max_relative_error(robust.gain, gain);
	CHECK(gain_error < 0.01);

	// The additive Δ's own target is what it measures without the person; the person shifts it.
	const LightingChange paper_clean = estimate_lighting_change(clean.before, clean.new_color, clean.visible, paper_options);
	const LightingChange paper_people = estimate_lighting_change(people.before, people.new_color, people.visible, paper_options);
	REQUIRE(paper_clean.valid);
	REQUIRE(paper_people.valid);
	CHECK(paper_people.gain == cv::Vec3f(1.0f, 1.0f, 1.0f));
	const double additive_bias = max_relative_error(paper_people.offset, paper_clean.offset);
	CHECK(additive_bias > 0.05);

	// How well each change predicts the new value of the inlier (non-person, valid) texels.
	double robust_residual = 0.0, paper_residual = 0.0;
	int count = 0;
	for (int y = 0; y < 100; y++) {
		for (int x = 0; x < 200; x++) {
			if (x >= 40 && x < 80) {
				continue;
			}
			const cv::Vec3f old_value = people.before.color.at<cv::Vec3f>(y, x);
			const cv::Vec3f new_value = people.new_color.at<cv::Vec3f>(y, x);
			if (!lighting_value_usable(old_value, robust_options) || !lighting_value_usable(new_value, robust_options)) {
				continue;
			}
			robust_residual += cv::norm(robust.apply(old_value) - new_value, cv::NORM_L1) / 3.0;
			paper_residual += cv::norm(paper_people.apply(old_value) - new_value, cv::NORM_L1) / 3.0;
			count++;
		}
	}
	robust_residual /= count;
	paper_residual /= count;
	CHECK(robust_residual < 0.5 * paper_residual);

	MESSAGE("true gain " << gain[0] << ", " << gain[1] << ", " << gain[2] << "; robust gain " << robust.gain[0] << ", " << robust.gain[1] << ", "
						 << robust.gain[2] << " (max relative error " << gain_error * 100.0 << " %, " << robust.sample_count << " samples)");
	MESSAGE("additive delta without person " << paper_clean.offset[0] << ", " << paper_clean.offset[1] << ", " << paper_clean.offset[2]
											 << "; with person " << paper_people.offset[0] << ", " << paper_people.offset[1] << ", " << paper_people.offset[2]
											 << " (max relative bias " << additive_bias * 100.0 << " %)");
	MESSAGE("mean abs prediction error on inlier texels: robust gain " << robust_residual << ", additive " << paper_residual);
}

TEST_CASE("lighting: the validity function excludes saturated, black, unobserved and not visible texels") {
	// 10 x 10 valid texels with new = old + 0.1; one texel of each kind of invalid with a huge
	// difference that would shift the mean if counted.
	CoarseTexture before = blank_texture(10, 10);
	cv::Mat new_color(10, 10, CV_32FC3);
	cv::Mat visible(10, 10, CV_8UC1, cv::Scalar(255));
	before.observed.setTo(255);
	for (int y = 0; y < 10; y++) {
		for (int x = 0; x < 10; x++) {
			const float v = 0.2f + 0.03f * static_cast<float>((x + y) % 10);
			before.color.at<cv::Vec3f>(y, x) = cv::Vec3f(v, v, v);
			new_color.at<cv::Vec3f>(y, x) = cv::Vec3f(v + 0.1f, v + 0.1f, v + 0.1f);
		}
	}
	LightingOptions options;
	options.model = LightingModel::ADDITIVE_PAPER;
	options.sample_step = 1;
	options.min_samples = 1;
	const LightingChange reference = estimate_lighting_change(before, new_color, visible, options);
	REQUIRE(reference.valid);
	CHECK(reference.sample_count == 100);
	CHECK(reference.offset[0] == doctest::Approx(0.1f).epsilon(1e-5));

	auto check_excluded = [&](const char *p_what, auto p_spoil) {
		CAPTURE(p_what);
		CoarseTexture spoilt_before = before;
		spoilt_before.color = before.color.clone();
		spoilt_before.observed = before.observed.clone();
		cv::Mat spoilt_new = new_color.clone();
		cv::Mat spoilt_visible = visible.clone();
		// Texel (3, 4) gets a wildly different new value, then is made invalid one way.
		spoilt_new.at<cv::Vec3f>(4, 3) = cv::Vec3f(0.9f, 0.9f, 0.9f);
		spoilt_before.color.at<cv::Vec3f>(4, 3) = cv::Vec3f(0.1f, 0.1f, 0.1f);
		p_spoil(&spoilt_before, &spoilt_new, &spoilt_visible);
		const LightingChange change = estimate_lighting_change(spoilt_before, spoilt_new, spoilt_visible, options);
		CHECK(change.sample_count == 99);
		for (int c = 0; c < 3; c++) {
			CHECK(change.offset[c] == doctest::Approx(0.1f).epsilon(1e-5));
		}
	};
	// Sanity: unspoilt, the outlier is counted and moves the mean.
	{
		CoarseTexture spoilt_before = before;
		spoilt_before.color = before.color.clone();
		spoilt_before.color.at<cv::Vec3f>(4, 3) = cv::Vec3f(0.1f, 0.1f, 0.1f);
		cv::Mat spoilt_new = new_color.clone();
		spoilt_new.at<cv::Vec3f>(4, 3) = cv::Vec3f(0.9f, 0.9f, 0.9f);
		const LightingChange change = estimate_lighting_change(spoilt_before, spoilt_new, visible, options);
		CHECK(change.sample_count == 100);
		CHECK(change.offset[0] > 0.105f);
	}
	check_excluded("new saturated", [](CoarseTexture *, cv::Mat *r_new, cv::Mat *) { r_new->at<cv::Vec3f>(4, 3)[1] = 1.0f; });
	check_excluded("old saturated", [](CoarseTexture *r_before, cv::Mat *, cv::Mat *) { r_before->color.at<cv::Vec3f>(4, 3)[2] = 250.5f / 255.0f; });
	check_excluded("new black", [](CoarseTexture *, cv::Mat *r_new, cv::Mat *) { r_new->at<cv::Vec3f>(4, 3)[0] = 0.0f; });
	check_excluded("old black", [](CoarseTexture *r_before, cv::Mat *, cv::Mat *) { r_before->color.at<cv::Vec3f>(4, 3) = cv::Vec3f(0.01f, 0.5f, 0.5f); });
	check_excluded("not observed (inpainted)", [](CoarseTexture *r_before, cv::Mat *, cv::Mat *) { r_before->observed.at<uint8_t>(4, 3) = 0; });
	check_excluded("not visible", [](CoarseTexture *, cv::Mat *, cv::Mat *r_visible) { r_visible->at<uint8_t>(4, 3) = 0; });
	check_excluded("NaN", [](CoarseTexture *, cv::Mat *r_new, cv::Mat *) { r_new->at<cv::Vec3f>(4, 3)[0] = std::nanf(""); });

	SUBCASE("thresholds are options") {
		LightingOptions loose = options;
		loose.saturated_threshold = 2.0f;
		cv::Mat spoilt_new = new_color.clone();
		spoilt_new.at<cv::Vec3f>(4, 3) = cv::Vec3f(1.0f, 1.0f, 1.0f);
		CHECK(estimate_lighting_change(before, spoilt_new, visible, loose).sample_count == 100);
		CHECK(estimate_lighting_change(before, spoilt_new, visible, options).sample_count == 99);
	}
	SUBCASE("sparse sampling: every k-th texel along x and y") {
		LightingOptions sparse = options;
		sparse.sample_step = 3;
		CHECK(estimate_lighting_change(before, new_color, visible, sparse).sample_count == 16); // x, y in {0, 3, 6, 9}.
	}
	SUBCASE("too few samples: identity") {
		LightingOptions strict = options;
		strict.min_samples = 101;
		const LightingChange change = estimate_lighting_change(before, new_color, visible, strict);
		CHECK_FALSE(change.valid);
		CHECK(change.offset == cv::Vec3f(0.0f, 0.0f, 0.0f));
		CHECK(change.gain == cv::Vec3f(1.0f, 1.0f, 1.0f));
	}
	SUBCASE("mismatched inputs: identity") {
		CHECK_FALSE(estimate_lighting_change(before, cv::Mat(5, 5, CV_32FC3), visible, options).valid);
	}
}

TEST_CASE("lighting: pairs API matches the image API") {
	std::vector<LightingSample> samples;
	for (int i = 0; i < 100; i++) {
		const float v = 0.1f + 0.005f * static_cast<float>(i);
		samples.push_back({ cv::Vec3f(v, v * 0.9f, v * 0.8f), cv::Vec3f(1.5f * v, 1.5f * v * 0.9f, 0.5f * v * 0.8f) });
	}
	samples.push_back({ cv::Vec3f(0.5f, 0.5f, 0.5f), cv::Vec3f(1.0f, 1.0f, 1.0f) }); // Saturated: dropped.
	const LightingChange change = estimate_lighting_change(samples);
	REQUIRE(change.valid);
	CHECK(change.sample_count == 100);
	CHECK(change.gain[0] == doctest::Approx(1.5f).epsilon(1e-4));
	CHECK(change.gain[1] == doctest::Approx(1.5f).epsilon(1e-4));
	CHECK(change.gain[2] == doctest::Approx(0.5f).epsilon(1e-4));
}

TEST_CASE("lighting: apply_lighting_change touches only observed texels not updated this frame") {
	CoarseTexture texture = blank_texture(8, 6);
	texture.color.setTo(cv::Scalar(0.2, 0.4, 0.6));
	texture.observed.setTo(255);
	texture.observed(cv::Rect(0, 0, 2, 6)).setTo(0); // Columns 0-1: never observed.
	texture.updated(cv::Rect(4, 0, 4, 6)).setTo(255); // Columns 4-7: updated this frame.

	SUBCASE("gain") {
		LightingChange change;
		change.valid = true;
		change.model = LightingModel::GAIN_ROBUST;
		change.gain = cv::Vec3f(2.0f, 0.5f, 1.0f);
		apply_lighting_change(&texture, change);
		for (int y = 0; y < 6; y++) {
			for (int x = 0; x < 8; x++) {
				const cv::Vec3f got = texture.color.at<cv::Vec3f>(y, x);
				const bool touched = x >= 2 && x < 4;
				CHECK(got == (touched ? cv::Vec3f(0.4f, 0.2f, 0.6f) : cv::Vec3f(0.2f, 0.4f, 0.6f)));
			}
		}
	}
	SUBCASE("additive, clamped at zero") {
		LightingChange change;
		change.valid = true;
		change.model = LightingModel::ADDITIVE_PAPER;
		change.offset = cv::Vec3f(0.1f, -0.5f, 0.0f);
		apply_lighting_change(&texture, change);
		const cv::Vec3f touched = texture.color.at<cv::Vec3f>(3, 3);
		CHECK(touched[0] == doctest::Approx(0.3f));
		CHECK(touched[1] == 0.0f);
		CHECK(touched[2] == doctest::Approx(0.6f));
		CHECK(texture.color.at<cv::Vec3f>(3, 0) == cv::Vec3f(0.2f, 0.4f, 0.6f));
		CHECK(texture.color.at<cv::Vec3f>(3, 5) == cv::Vec3f(0.2f, 0.4f, 0.6f));
	}
	SUBCASE("invalid change: nothing") {
		LightingChange change;
		change.gain = cv::Vec3f(3.0f, 3.0f, 3.0f);
		apply_lighting_change(&texture, change);
		CHECK(texture.color.at<cv::Vec3f>(3, 3) == cv::Vec3f(0.2f, 0.4f, 0.6f));
	}
}

TEST_CASE("lighting: changes compose, and the change since a reference undoes it") {
	LightingChange first;
	first.valid = true;
	first.gain = cv::Vec3f(2.0f, 1.5f, 1.0f);
	first.offset = cv::Vec3f(0.0f, 0.1f, -0.05f);
	LightingChange then;
	then.valid = true;
	then.gain = cv::Vec3f(0.5f, 1.0f, 3.0f);
	then.offset = cv::Vec3f(0.2f, 0.0f, 0.1f);
	const cv::Vec3f x(0.3f, 0.4f, 0.5f);
	const LightingChange both = compose_lighting(then, first);
	const cv::Vec3f direct = then.apply(first.apply(x));
	const cv::Vec3f composed = both.apply(x);
	for (int c = 0; c < 3; c++) {
		CHECK(composed[c] == doctest::Approx(direct[c]).epsilon(1e-6));
	}
	// What was observed under `first` and is now under `both` changed by exactly `then`.
	const LightingChange since = lighting_since(both, first);
	const cv::Vec3f y = first.apply(x);
	for (int c = 0; c < 3; c++) {
		CHECK(since.apply(y)[c] == doctest::Approx(then.apply(y)[c]).epsilon(1e-6));
	}
}

TEST_CASE("lighting: the robust gain's medians over a strided subset give the gain of all samples") {
	std::mt19937 rng(7);
	const cv::Vec3f gain(0.7f, 1.1f, 1.45f);
	const Scene people = gain_scene(gain, true, &rng);
	LightingOptions all_options, subset_options;
	all_options.scale_samples = 0;
	subset_options.scale_samples = 300; // of about 3 700 valid samples (every second texel each way)
	const LightingChange all = estimate_lighting_change(people.before, people.new_color, people.visible, all_options);
	const LightingChange subset = estimate_lighting_change(people.before, people.new_color, people.visible, subset_options);
	REQUIRE(all.valid);
	REQUIRE(subset.valid);
	CHECK(all.sample_count > 10 * subset_options.scale_samples);
	CHECK(max_relative_error(all.gain, gain) < 0.01);
	CHECK(max_relative_error(subset.gain, all.gain) < 1e-3);
}
