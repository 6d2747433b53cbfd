#pragma once
// A small dense Levenberg-Marquardt for the camera code's fits (a dozen parameters, thousands of
// residuals): the unified model fitted to OCamCalib's, and board poses in the tests.

#include <functional>
#include <vector>

namespace roomprobe {

// Fills r_residuals (resized by the callee) for the parameters; false when they are unusable
// (the step is then rejected, as a worse one would be).
using ResidualFunction = std::function<bool(const std::vector<double> &p_params, std::vector<double> &r_residuals)>;

struct LeastSquaresOptions {
	int max_iterations = 200;
	double initial_lambda = 1e-3; // Marquardt's damping, relative to diag(J^T J)
	double relative_tolerance = 1e-14; // stop when a step lowers the cost by less than this, relatively
	// Central-difference steps for the numerical Jacobian, one per parameter; empty: 1e-6 * max(1, |p|).
	std::vector<double> steps;
};

struct LeastSquaresResult {
	bool ok = false; // false only when the residuals could not be evaluated at the start
	int iterations = 0;
	double initial_cost = 0.0; // sum of squared residuals
	double final_cost = 0.0;
	int residual_count = 0;
};

// The standard deviation of each parameter at a least-squares minimum p_params: the square roots
// of diag((J^T J)^-1) times the residuals' variance (sum of squares over m - n), J numerical as in
// the fit. Empty when the residuals cannot be evaluated or there are no more residuals than
// parameters. Meaningful when the residuals are independent, zero-mean and of one scale.
std::vector<double> parameter_std_devs(const ResidualFunction &p_function, const std::vector<double> &p_params, const std::vector<double> &p_steps = {});

// Minimizes the sum of squared residuals over r_params (in place).
LeastSquaresResult minimize_least_squares(const ResidualFunction &p_function, std::vector<double> &r_params,
		const LeastSquaresOptions &p_options = {});

} // namespace roomprobe
