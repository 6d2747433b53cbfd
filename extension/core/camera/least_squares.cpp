#include "least_squares.h"

#include <io/opencv.h>

#include <algorithm>
#include <cmath>

namespace roomprobe {

namespace {

double sum_of_squares(const std::vector<double> &p_values) {
	double sum = 0.0;
	for (double value : p_values) {
		sum += value * value;
	}
	return sum;
}

// Central differences: the fits are smooth, and this keeps the Jacobian accurate to ~1e-10.
bool numerical_jacobian(const ResidualFunction &p_function, const std::vector<double> &p_params, const std::vector<double> &p_steps, int p_m,
		cv::Mat &r_jacobian) {
	const int n = int(p_params.size());
	r_jacobian.create(p_m, n, CV_64F);
	std::vector<double> probe, plus, minus;
	for (int k = 0; k < n; k++) {
		const double h = k < int(p_steps.size()) ? p_steps[k] : 1e-6 * std::max(1.0, std::abs(p_params[k]));
		probe = p_params;
		probe[k] = p_params[k] + h;
		if (!p_function(probe, plus) || int(plus.size()) != p_m) {
			return false;
		}
		probe[k] = p_params[k] - h;
		if (!p_function(probe, minus) || int(minus.size()) != p_m) {
			return false;
		}
		for (int i = 0; i < p_m; i++) {
			r_jacobian.at<double>(i, k) = (plus[i] - minus[i]) / (2.0 * h);
		}
	}
	return true;
}

} // namespace

std::vector<double> parameter_std_devs(const ResidualFunction &p_function, const std::vector<double> &p_params, const std::vector<double> &p_steps) {
	std::vector<double> residuals;
	if (!p_function(p_params, residuals)) {
		return {};
	}
	const int m = int(residuals.size());
	const int n = int(p_params.size());
	cv::Mat jacobian;
	if (m <= n || !numerical_jacobian(p_function, p_params, p_steps, m, jacobian)) {
		return {};
	}
	cv::Mat covariance;
	if (cv::invert(jacobian.t() * jacobian, covariance, cv::DECOMP_SVD) == 0.0) {
		return {};
	}
	const double variance = sum_of_squares(residuals) / double(m - n); // of one residual
	std::vector<double> result(n);
	for (int k = 0; k < n; k++) {
		result[k] = std::sqrt(std::max(0.0, covariance.at<double>(k, k) * variance));
	}
	return result;
}

LeastSquaresResult minimize_least_squares(const ResidualFunction &p_function, std::vector<double> &r_params,
		const LeastSquaresOptions &p_options) {
	LeastSquaresResult result;
	const int n = int(r_params.size());
	std::vector<double> residuals;
	if (!p_function(r_params, residuals) || !std::isfinite(sum_of_squares(residuals))) {
		return result;
	}
	const int m = int(residuals.size());
	result.ok = true;
	result.residual_count = m;
	result.initial_cost = result.final_cost = sum_of_squares(residuals);
	double lambda = p_options.initial_lambda;
	cv::Mat jacobian;
	for (int iteration = 0; iteration < p_options.max_iterations; iteration++) {
		result.iterations = iteration + 1;
		const bool jacobian_ok = numerical_jacobian(p_function, r_params, p_options.steps, m, jacobian);
		if (!jacobian_ok) {
			break;
		}
		const cv::Mat jtj = jacobian.t() * jacobian;
		const cv::Mat jtr = jacobian.t() * cv::Mat(residuals);
		bool stepped = false;
		while (!stepped && lambda < 1e16) {
			cv::Mat damped = jtj.clone();
			for (int k = 0; k < n; k++) {
				damped.at<double>(k, k) += lambda * std::max(jtj.at<double>(k, k), 1e-12);
			}
			cv::Mat delta;
			if (!cv::solve(damped, -jtr, delta, cv::DECOMP_CHOLESKY) && !cv::solve(damped, -jtr, delta, cv::DECOMP_SVD)) {
				lambda *= 10.0;
				continue;
			}
			std::vector<double> candidate = r_params;
			for (int k = 0; k < n; k++) {
				candidate[k] += delta.at<double>(k);
			}
			std::vector<double> candidate_residuals;
			if (p_function(candidate, candidate_residuals) && int(candidate_residuals.size()) == m) {
				const double cost = sum_of_squares(candidate_residuals);
				if (std::isfinite(cost) && cost < result.final_cost) {
					const double gain = (result.final_cost - cost) / std::max(result.final_cost, 1e-300);
					r_params = candidate;
					residuals = candidate_residuals;
					result.final_cost = cost;
					lambda = std::max(lambda * 0.1, 1e-12);
					stepped = true;
					if (gain < p_options.relative_tolerance) {
						return result;
					}
					continue;
				}
			}
			lambda *= 10.0;
		}
		if (!stepped) {
			break; // no damping lowers the cost: a minimum, to double precision
		}
	}
	return result;
}

} // namespace roomprobe
