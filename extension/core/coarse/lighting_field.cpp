#include "lighting_field.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>

namespace roomprobe {

namespace {

// The upper median, on a copy (the caller's order is kept).
double median_in(std::vector<double> p_values) {
	const size_t mid = p_values.size() / 2;
	std::nth_element(p_values.begin(), p_values.begin() + std::ptrdiff_t(mid), p_values.end());
	return p_values[mid];
}

} // namespace

bool fit_lighting_field(const std::vector<LightingSample> &p_valid, const cv::Vec3d &p_gains, const LightingOptions &p_options,
		LightingChange *r_change) {
	const size_t n = p_valid.size();
	if (n < size_t(std::max(p_options.min_samples, 8)) || !(p_options.field_prior_per_m > 0.0)) {
		return false;
	}
	// Log ratios per channel, their channel mean, and the positions about their mean.
	std::vector<cv::Vec3d> log_ratio(n), offset(n);
	std::vector<double> mean_log(n);
	cv::Vec3d centre(0.0, 0.0, 0.0);
	for (size_t i = 0; i < n; i++) {
		for (int c = 0; c < 3; c++) {
			log_ratio[i][c] = std::log(double(p_valid[i].new_value[c]) / double(p_valid[i].old_value[c]));
		}
		mean_log[i] = (log_ratio[i][0] + log_ratio[i][1] + log_ratio[i][2]) / 3.0;
		offset[i] = cv::Vec3d(p_valid[i].position[0], p_valid[i].position[1], p_valid[i].position[2]);
		centre += offset[i];
	}
	centre *= 1.0 / double(n);
	for (cv::Vec3d &d : offset) {
		d -= centre;
	}
	double b = (std::log(p_gains[0]) + std::log(p_gains[1]) + std::log(p_gains[2])) / 3.0;
	cv::Vec3d slope(0.0, 0.0, 0.0);
	std::vector<double> weight(n, 1.0), residual(n), magnitude(n);
	for (int iteration = 0; iteration < 8; iteration++) {
		for (size_t i = 0; i < n; i++) {
			residual[i] = mean_log[i] - b - slope.dot(offset[i]);
			magnitude[i] = std::abs(residual[i]);
		}
		const double sigma = std::max(1.4826 * median_in(magnitude), 1e-4);
		const double cutoff = p_options.tukey_c * sigma;
		// Weighted normal equations of (b, s) with the prior's ridge on s: sigma^2 / prior^2.
		cv::Matx44d a = cv::Matx44d::zeros();
		cv::Vec4d rhs(0.0, 0.0, 0.0, 0.0);
		for (size_t i = 0; i < n; i++) {
			const double u = residual[i] / cutoff;
			const double root = std::max(1.0 - u * u, 0.0);
			weight[i] = root * root;
			const cv::Vec4d row(1.0, offset[i][0], offset[i][1], offset[i][2]);
			a += weight[i] * (row * row.t());
			rhs += weight[i] * mean_log[i] * row;
		}
		const double ridge = sigma * sigma / (p_options.field_prior_per_m * p_options.field_prior_per_m);
		for (int k = 1; k < 4; k++) {
			a(k, k) += ridge;
		}
		cv::Vec4d solution;
		if (!cv::solve(a, rhs, solution, cv::DECOMP_CHOLESKY)) {
			return false;
		}
		b = solution[0];
		slope = cv::Vec3d(solution[1], solution[2], solution[3]);
		const double length = cv::norm(slope);
		if (length > p_options.field_max_per_m) {
			slope *= p_options.field_max_per_m / length;
		}
	}
	// Each channel's level at the centre: the weighted mean of its log ratios less the field.
	for (int c = 0; c < 3; c++) {
		double sum = 0.0, sum_weight = 0.0;
		for (size_t i = 0; i < n; i++) {
			sum += weight[i] * (log_ratio[i][c] - slope.dot(offset[i]));
			sum_weight += weight[i];
		}
		if (!(sum_weight > 0.0)) {
			return false;
		}
		r_change->gain[c] = float(std::exp(sum / sum_weight - slope.dot(centre)));
	}
	r_change->log_slope = cv::Vec3f(float(slope[0]), float(slope[1]), float(slope[2]));
	return true;
}

} // namespace roomprobe
