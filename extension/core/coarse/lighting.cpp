#include "lighting.h"

#include "lighting_field.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace roomprobe {

namespace {

double median_of(std::vector<double> *r_values) {
	std::vector<double> &values = *r_values;
	const size_t mid = values.size() / 2;
	std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
	double median = values[mid];
	if (values.size() % 2 == 0) {
		median = 0.5 * (median + *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid)));
	}
	return median;
}

// One chunk's IRLS sums, per channel: sum w · old · new and sum w · old².
struct WeightedSums {
	double numerator[3] = { 0.0, 0.0, 0.0 };
	double denominator[3] = { 0.0, 0.0, 0.0 };
};

// The robust gains of the three channels, new ≈ g · old each, fitted in lockstep: one pass over
// the pairs an iteration serves all three (six independent sums). The medians (the start and each
// iteration's scale) are taken over an evenly strided subset of at most scale_samples pairs: a
// median needs a selection, the costliest step, and a few thousand samples fix it well; the
// weighted least squares use every pair.
cv::Vec3d robust_gains(const std::vector<LightingSample> &p_samples, const LightingOptions &p_options) {
	const size_t n = p_samples.size();
	const size_t limit = size_t(std::max(p_options.scale_samples, 1));
	const size_t stride = p_options.scale_samples > 0 && n > limit ? (n + limit - 1) / limit : 1;
	std::vector<double> work;
	work.reserve(n / stride + 1);
	double gain[3];
	bool done[3] = { false, false, false };
	const size_t chunk_size = 4096;
	const size_t chunks = (n + chunk_size - 1) / chunk_size;
	std::vector<WeightedSums> chunk_sums(chunks);
	for (int c = 0; c < 3; c++) {
		work.clear();
		for (size_t i = 0; i < n; i += stride) {
			work.push_back(static_cast<double>(p_samples[i].new_value[c]) / static_cast<double>(p_samples[i].old_value[c]));
		}
		gain[c] = median_of(&work);
	}
	for (int iteration = 0; iteration < p_options.irls_iterations; iteration++) {
		double inverse_cutoff[3] = { 0.0, 0.0, 0.0 };
		for (int c = 0; c < 3; c++) {
			if (done[c]) {
				continue;
			}
			work.clear();
			for (size_t i = 0; i < n; i += stride) {
				work.push_back(std::abs(p_samples[i].new_value[c] - gain[c] * p_samples[i].old_value[c]));
			}
			const double sigma = 1.4826 * median_of(&work);
			if (!(sigma > 1e-12)) {
				done[c] = true; // Inliers fit exactly: the current gain is the answer.
				continue;
			}
			inverse_cutoff[c] = 1.0 / (p_options.tukey_c * sigma);
		}
		if (done[0] && done[1] && done[2]) {
			break;
		}
		// The weighted sums in fixed chunks, in parallel, added in chunk order: the same result
		// whatever the threads.
		tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks), [&](const tbb::blocked_range<size_t> &p_chunks) {
			for (size_t k = p_chunks.begin(); k < p_chunks.end(); k++) {
				WeightedSums sums;
				for (size_t i = k * chunk_size; i < std::min(n, (k + 1) * chunk_size); i++) {
					const LightingSample &sample = p_samples[i];
					for (int c = 0; c < 3; c++) {
						// Tukey's biweight (1 - u^2)^2 for |u| < 1, else 0, without a branch.
						const double old_value = sample.old_value[c], new_value = sample.new_value[c];
						const double u = (new_value - gain[c] * old_value) * inverse_cutoff[c];
						const double root = std::max(1.0 - u * u, 0.0);
						const double weight = root * root;
						sums.numerator[c] += weight * old_value * new_value;
						sums.denominator[c] += weight * old_value * old_value;
					}
				}
				chunk_sums[k] = sums;
			}
		});
		double numerator[3] = { 0.0, 0.0, 0.0 };
		double denominator[3] = { 0.0, 0.0, 0.0 };
		for (const WeightedSums &sums : chunk_sums) {
			for (int c = 0; c < 3; c++) {
				numerator[c] += sums.numerator[c];
				denominator[c] += sums.denominator[c];
			}
		}
		for (int c = 0; c < 3; c++) {
			if (done[c]) {
				continue;
			}
			if (!(denominator[c] > 0.0)) {
				done[c] = true;
				continue;
			}
			const double next = numerator[c] / denominator[c];
			done[c] = std::abs(next - gain[c]) <= 1e-7 * std::abs(gain[c]);
			gain[c] = next;
		}
	}
	return cv::Vec3d(gain[0], gain[1], gain[2]);
}

// gain · p_old + offset per channel, clamped at 0 (radiance is not negative).
cv::Vec3f changed(const cv::Vec3f &p_old, const cv::Vec3f &p_gain, const cv::Vec3f &p_offset) {
	cv::Vec3f out;
	for (int c = 0; c < 3; c++) {
		out[c] = std::max(0.0f, p_gain[c] * p_old[c] + p_offset[c]);
	}
	return out;
}

} // namespace

cv::Vec3f LightingChange::apply(const cv::Vec3f &p_old) const {
	return changed(p_old, gain, offset);
}

cv::Vec3f LightingChange::gain_at(const glm::vec3 &p_position) const {
	const float field = std::exp(log_slope[0] * p_position.x + log_slope[1] * p_position.y + log_slope[2] * p_position.z);
	return gain * field;
}

cv::Vec3f LightingChange::apply(const cv::Vec3f &p_old, const glm::vec3 &p_position) const {
	return changed(p_old, has_field() ? gain_at(p_position) : gain, offset);
}

bool lighting_value_usable(const cv::Vec3f &p_value, const LightingOptions &p_options) {
	for (int c = 0; c < 3; c++) {
		// Written so that NaN is rejected too.
		if (!(p_value[c] < p_options.saturated_threshold) || !(p_value[c] > p_options.black_threshold)) {
			return false;
		}
	}
	return true;
}

LightingChange estimate_lighting_change(const std::vector<LightingSample> &p_samples, const LightingOptions &p_options) {
	LightingChange change;
	change.model = p_options.model;
	std::vector<LightingSample> valid;
	valid.reserve(p_samples.size());
	for (const LightingSample &sample : p_samples) {
		if (lighting_value_usable(sample.old_value, p_options) && lighting_value_usable(sample.new_value, p_options)) {
			valid.push_back(sample);
		}
	}
	change.sample_count = static_cast<int>(valid.size());
	if (valid.empty() || change.sample_count < p_options.min_samples) {
		return change;
	}
	if (p_options.model == LightingModel::ADDITIVE_PAPER) {
		cv::Vec3d sum(0.0, 0.0, 0.0);
		for (const LightingSample &sample : valid) {
			for (int c = 0; c < 3; c++) {
				sum[c] += static_cast<double>(sample.new_value[c]) - static_cast<double>(sample.old_value[c]);
			}
		}
		for (int c = 0; c < 3; c++) {
			change.offset[c] = static_cast<float>(sum[c] / static_cast<double>(valid.size()));
		}
	} else {
		const cv::Vec3d gains = robust_gains(valid, p_options);
		for (int c = 0; c < 3; c++) {
			change.gain[c] = static_cast<float>(gains[c]);
		}
		const bool positioned = std::all_of(valid.begin(), valid.end(), [](const LightingSample &p_sample) {
			return std::isfinite(p_sample.position[0]) && std::isfinite(p_sample.position[1]) && std::isfinite(p_sample.position[2]);
		});
		if (positioned && p_options.field_prior_per_m > 0.0) {
			fit_lighting_field(valid, gains, p_options, &change);
		}
	}
	change.valid = true;
	return change;
}

LightingChange estimate_lighting_change(const CoarseTexture &p_texture_before, const cv::Mat &p_new_color, const cv::Mat &p_visible,
		const LightingOptions &p_options) {
	const cv::Mat &old_color = p_texture_before.color;
	const cv::Mat &observed = p_texture_before.observed;
	if (old_color.type() != CV_32FC3 || p_new_color.type() != CV_32FC3 || observed.type() != CV_8UC1 || p_visible.type() != CV_8UC1 ||
			p_new_color.size() != old_color.size() || observed.size() != old_color.size() || p_visible.size() != old_color.size()) {
		LightingChange change;
		change.model = p_options.model;
		return change;
	}
	const int step = std::max(1, p_options.sample_step);
	std::vector<LightingSample> samples;
	samples.reserve(static_cast<size_t>(old_color.rows / step + 1) * static_cast<size_t>(old_color.cols / step + 1));
	for (int y = 0; y < old_color.rows; y += step) {
		const cv::Vec3f *old_row = old_color.ptr<cv::Vec3f>(y);
		const cv::Vec3f *new_row = p_new_color.ptr<cv::Vec3f>(y);
		const uint8_t *observed_row = observed.ptr<uint8_t>(y);
		const uint8_t *visible_row = p_visible.ptr<uint8_t>(y);
		for (int x = 0; x < old_color.cols; x += step) {
			if (observed_row[x] != 0 && visible_row[x] != 0) {
				samples.push_back({ old_row[x], new_row[x] });
			}
		}
	}
	return estimate_lighting_change(samples, p_options);
}

void apply_lighting_change(CoarseTexture *r_texture, const LightingChange &p_change, const std::vector<glm::dvec3> *p_points) {
	if (!r_texture || !p_change.valid) {
		return;
	}
	cv::Mat &color = r_texture->color;
	const cv::Mat &observed = r_texture->observed;
	const cv::Mat &updated = r_texture->updated;
	if (color.type() != CV_32FC3 || observed.type() != CV_8UC1 || updated.type() != CV_8UC1 || observed.size() != color.size() ||
			updated.size() != color.size()) {
		return;
	}
	// A field needs each texel's point; without them, its gain at the world origin (never wanted:
	// the pipeline passes the points).
	const bool field = p_change.has_field() && p_points != nullptr && p_points->size() == color.total();
	tbb::parallel_for(tbb::blocked_range<int>(0, color.rows), [&](const tbb::blocked_range<int> &p_rows) {
		for (int y = p_rows.begin(); y < p_rows.end(); y++) {
			cv::Vec3f *color_row = color.ptr<cv::Vec3f>(y);
			const uint8_t *observed_row = observed.ptr<uint8_t>(y);
			const uint8_t *updated_row = updated.ptr<uint8_t>(y);
			for (int x = 0; x < color.cols; x++) {
				if (observed_row[x] != 0 && updated_row[x] == 0) {
					if (field) {
						const glm::dvec3 &p = (*p_points)[size_t(y) * size_t(color.cols) + size_t(x)];
						color_row[x] = p_change.apply(color_row[x], glm::vec3(p));
					} else {
						color_row[x] = p_change.apply(color_row[x]);
					}
				}
			}
		}
	});
}

LightingChange compose_lighting(const LightingChange &p_then, const LightingChange &p_first) {
	LightingChange out;
	out.valid = p_then.valid && p_first.valid;
	out.model = p_then.model;
	out.sample_count = p_then.sample_count;
	for (int c = 0; c < 3; c++) {
		out.gain[c] = p_then.gain[c] * p_first.gain[c];
		out.offset[c] = p_then.gain[c] * p_first.offset[c] + p_then.offset[c];
	}
	out.log_slope = p_then.log_slope + p_first.log_slope;
	return out;
}

LightingChange lighting_since(const LightingChange &p_now, const LightingChange &p_reference) {
	LightingChange out = p_now;
	for (int c = 0; c < 3; c++) {
		// A gain of 0 (everything black) cannot be undone: treat it as no change since.
		const float g = p_reference.gain[c] > 0.0f ? p_now.gain[c] / p_reference.gain[c] : 1.0f;
		out.gain[c] = g;
		out.offset[c] = p_now.offset[c] - g * p_reference.offset[c];
	}
	out.log_slope = p_now.log_slope - p_reference.log_slope;
	return out;
}

} // namespace roomprobe
