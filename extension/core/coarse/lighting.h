#pragma once
// Reacting to large-scale lighting changes (paper §4.6).
//
// Before a fisheye frame is integrated, the change of the room's lighting since the previous
// frame is estimated from the texels the frame sees, and applied to the texels it does not update.
//
// The paper's model (ADDITIVE_PAPER): an RGB offset
//   Δ = Σ_t v(t) (F(f(t)) − T(t)) / Σ_t v(t),
// T the texture, F(f(t)) the fisheye value the texel samples this frame, v(t) the validity:
//   v(t) = 1 iff t is visible to the fisheye this frame, T(t) and F(f(t)) are neither saturated
//            nor black, and t has been observed directly (not inpainted); 0 otherwise.
// Applied as T(t) += Δ to the texels not updated this frame.
//
// Beyond the paper (GAIN_ROBUST, the default): a per-channel gain, new ≈ g · old. A light turned
// on or a curtain opened scales the radiance each surface reflects (for a fixed surface albedo,
// reflected radiance is proportional to irradiance), so a gain fits better than an offset, which
// brightens dark and bright surfaces by the same amount and can drive dark texels negative. The
// mean is also not robust: a person walking through the fisheye's view changes many texels by
// amounts unrelated to the lighting, and biases Δ. The gain is estimated robustly: start from the
// median of the ratios new / old (50 % breakdown point), then refine by iteratively reweighted
// least squares with Tukey's biweight on the residuals new − g · old (scale: 1.4826 · MAD), which
// gives outliers zero weight while using all inliers efficiently. The medians (the start and each
// iteration's scale) are taken over an evenly strided subset of at most scale_samples pairs.
//
// Saturated / black: a texel's colour is rejected when ANY channel of the old or the new value is
// >= saturated_threshold or <= black_threshold (a clipped channel's true value is unknown, and a
// near-zero old value makes a ratio meaningless). Defaults assume the texture's 8-bit units
// (1.0 = 255); for HDR frames set saturated_threshold to infinity.
//
// Sparse sampling: only texels with x % sample_step == 0 and y % sample_step == 0 are considered
// (1 / sample_step² of the atlas).

#include <coarse/coarse_texture.h>

#include <io/opencv.h>

#include <glm/vec3.hpp>

#include <cmath>

#include <vector>

namespace roomprobe {

enum class LightingModel {
	ADDITIVE_PAPER, // Paper §4.6: mean offset Δ over valid texels.
	GAIN_ROBUST, // Per-channel gain: median of ratios, refined by Tukey-biweight IRLS.
};

struct LightingOptions {
	LightingModel model = LightingModel::GAIN_ROBUST;
	float saturated_threshold = 250.0f / 255.0f; // A channel >= this is saturated.
	float black_threshold = 5.0f / 255.0f; // A channel <= this is black.
	int sample_step = 2; // Sample every sample_step-th texel along x and along y; >= 1.
	int min_samples = 32; // Fewer valid samples: no change is estimated (identity, valid = false).
	int irls_iterations = 10; // GAIN_ROBUST refinement iterations; 0: the median of ratios only.
	// GAIN_ROBUST: the median of ratios and each iteration's scale (MAD) are taken over at most
	// this many of the valid samples (evenly strided); the weighted fit uses all of them. A median
	// needs a selection, the estimate's costliest step; 0: all samples.
	int scale_samples = 2048;
	double tukey_c = 4.685; // Tukey biweight cut-off, in robust standard deviations.
	// GAIN_ROBUST, beyond one gain (issue #42): a gain field, log g(x) = log g + slope . x, fitted
	// to the pairs' positions where every pair has one. A light switched on brightens the near
	// side of the room more than the far side; one gain cannot. The slope has a Gaussian prior of
	// this standard deviation (log gain per metre), so a frame whose pairs span little of the room,
	// or agree on one gain, keeps about one gain. 0: one gain only.
	double field_prior_per_m = 0.0;
	double field_max_per_m = 1.0; // the slope's length is clamped to this (log gain per metre)
};

// One texel's old texture value T(t) and newly sampled fisheye value F(f(t)), linear RGB, and
// where the texel is (world metres; NaN: unknown, and no gain field is fitted).
struct LightingSample {
	cv::Vec3f old_value;
	cv::Vec3f new_value;
	cv::Vec3f position = cv::Vec3f(NAN, NAN, NAN);
};

struct LightingChange {
	bool valid = false; // False: too few valid samples; the change is the identity.
	LightingModel model = LightingModel::GAIN_ROBUST;
	cv::Vec3f offset = cv::Vec3f(0.0f, 0.0f, 0.0f); // ADDITIVE_PAPER: Δ, per channel.
	cv::Vec3f gain = cv::Vec3f(1.0f, 1.0f, 1.0f); // GAIN_ROBUST: g, per channel (at the world origin with a field).
	// GAIN_ROBUST with a field: d log g / dx, shared by the channels, per metre (0: one gain).
	cv::Vec3f log_slope = cv::Vec3f(0.0f, 0.0f, 0.0f);
	int sample_count = 0; // Valid samples used.

	// The changed value: gain · p_old + offset, clamped at 0 (radiance is not negative). Without
	// a position, a field's gain is its value at the world origin: use the overload below.
	cv::Vec3f apply(const cv::Vec3f &p_old) const;
	// The same at world point p_position (metres).
	cv::Vec3f apply(const cv::Vec3f &p_old, const glm::vec3 &p_position) const;
	bool has_field() const { return log_slope != cv::Vec3f(0.0f, 0.0f, 0.0f); }
	// The gain at p_position, per channel.
	cv::Vec3f gain_at(const glm::vec3 &p_position) const;
};

// The change p_then applied after p_first: gain_then * (gain_first * x + offset_first) + offset_then
// (without the clamp at 0); fields' slopes add. Valid when both are. (A field after an offset
// would make the offset depend on position; a pipeline uses one model, so that never happens.)
LightingChange compose_lighting(const LightingChange &p_then, const LightingChange &p_first);
// The change that takes colours from p_reference to p_now: p_now after the inverse of p_reference.
LightingChange lighting_since(const LightingChange &p_now, const LightingChange &p_reference);

// v(t)'s colour part: true when no channel of p_value is saturated or black.
bool lighting_value_usable(const cv::Vec3f &p_value, const LightingOptions &p_options);

// From (old, new) pairs whose texels are already known to be visible and directly observed; the
// saturated / black test is applied here. No sparse sampling (the caller chose the pairs).
LightingChange estimate_lighting_change(const std::vector<LightingSample> &p_samples, const LightingOptions &p_options = LightingOptions());

// From atlas-aligned images: p_texture_before.color is T (CV_32FC3) and p_texture_before.observed
// the directly-observed mask (CV_8UC1, 255 = observed, inpainted texels are 0); p_new_color is
// F(f(t)) resampled into the atlas (CV_32FC3, same size), and p_visible (CV_8UC1, same size) is
// 255 where the texel is visible to the fisheye this frame and p_new_color holds a sample. Returns
// an invalid (identity) change when the sizes or types do not match.
LightingChange estimate_lighting_change(const CoarseTexture &p_texture_before, const cv::Mat &p_new_color, const cv::Mat &p_visible,
		const LightingOptions &p_options = LightingOptions());

// Applies p_change to every texel of r_texture->color that has been observed and was NOT updated
// this frame (r_texture->updated == 0). Never-observed texels hold no data (the inpainter fills
// them from the observed ones) and are left alone. Does nothing for an invalid change.
// p_points: each texel's world point (TexelGeometry::points), needed for a field.
void apply_lighting_change(CoarseTexture *r_texture, const LightingChange &p_change, const std::vector<glm::dvec3> *p_points = nullptr);

} // namespace roomprobe
