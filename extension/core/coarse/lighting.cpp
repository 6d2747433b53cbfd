#include "lighting.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

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

// Robust gain for one channel: new ≈ g · old.
double robust_gain(const std::vector<LightingSample> &p_samples, int p_channel, const LightingOptions &p_options) {
	std::vector<double> work;
	work.reserve(p_samples.size());
	for (const LightingSample &sample : p_samples) {
		work.push_back(static_cast<double>(sample.new_value[p_channel]) / static_cast<double>(sample.old_value[p_channel]));
	}
	double gain = median_of(&work);
	for (int iteration = 0; iteration < p_options.irls_iterations; iteration++) {
		work.clear();
		for (const LightingSample &sample : p_samples) {
			work.push_back(std::abs(sample.new_value[p_channel] - gain * sample.old_value[p_channel]));
		}
		const double sigma = 1.4826 * median_of(&work);
		if (!(sigma > 1e-12)) {
			break; // Inliers fit exactly: the current gain is the answer.
		}
		const double cutoff = p_options.tukey_c * sigma;
		double numerator = 0.0;
		double denominator = 0.0;
		for (const LightingSample &sample : p_samples) {
			const double old_value = sample.old_value[p_channel];
			const double residual = sample.new_value[p_channel] - gain * old_value;
			const double u = residual / cutoff;
			if (std::abs(u) >= 1.0) {
				continue;
			}
			const double weight = (1.0 - u * u) * (1.0 - u * u);
			numerator += weight * old_value * sample.new_value[p_channel];
			denominator += weight * old_value * old_value;
		}
		if (!(denominator > 0.0)) {
			break;
		}
		const double next = numerator / denominator;
		const bool converged = std::abs(next - gain) <= 1e-7 * std::abs(gain);
		gain = next;
		if (converged) {
			break;
		}
	}
	return gain;
}

} // namespace

cv::Vec3f LightingChange::apply(const cv::Vec3f &p_old) const {
	cv::Vec3f out;
	for (int c = 0; c < 3; c++) {
		out[c] = std::max(0.0f, gain[c] * p_old[c] + offset[c]);
	}
	return out;
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
		for (int c = 0; c < 3; c++) {
			change.gain[c] = static_cast<float>(robust_gain(valid, c, p_options));
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

void apply_lighting_change(CoarseTexture *r_texture, const LightingChange &p_change) {
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
	for (int y = 0; y < color.rows; y++) {
		cv::Vec3f *color_row = color.ptr<cv::Vec3f>(y);
		const uint8_t *observed_row = observed.ptr<uint8_t>(y);
		const uint8_t *updated_row = updated.ptr<uint8_t>(y);
		for (int x = 0; x < color.cols; x++) {
			if (observed_row[x] != 0 && updated_row[x] == 0) {
				color_row[x] = p_change.apply(color_row[x]);
			}
		}
	}
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
	return out;
}

} // namespace roomprobe
