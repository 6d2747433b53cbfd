#include "radtan.h"

#include <cmath>

namespace roomprobe {

glm::dvec2 radtan_distort(const Radtan &p_d, const glm::dvec2 &p_x) {
	const double x = p_x.x, y = p_x.y;
	const double r2 = x * x + y * y;
	const double radial = 1.0 + r2 * (p_d.k1 + r2 * (p_d.k2 + r2 * p_d.k3));
	return { x * radial + 2.0 * p_d.p1 * x * y + p_d.p2 * (r2 + 2.0 * x * x),
		y * radial + p_d.p1 * (r2 + 2.0 * y * y) + 2.0 * p_d.p2 * x * y };
}

glm::dvec2 radtan_distort(const Radtan &p_d, const glm::dvec2 &p_x, double r_jacobian[4]) {
	const double x = p_x.x, y = p_x.y;
	const double r2 = x * x + y * y;
	const double radial = 1.0 + r2 * (p_d.k1 + r2 * (p_d.k2 + r2 * p_d.k3));
	const double d_radial = p_d.k1 + r2 * (2.0 * p_d.k2 + 3.0 * r2 * p_d.k3); // d radial / d r2
	r_jacobian[0] = radial + 2.0 * x * x * d_radial + 2.0 * p_d.p1 * y + 6.0 * p_d.p2 * x;
	r_jacobian[1] = 2.0 * x * y * d_radial + 2.0 * p_d.p1 * x + 2.0 * p_d.p2 * y;
	r_jacobian[2] = 2.0 * x * y * d_radial + 2.0 * p_d.p1 * x + 2.0 * p_d.p2 * y;
	r_jacobian[3] = radial + 2.0 * y * y * d_radial + 6.0 * p_d.p1 * y + 2.0 * p_d.p2 * x;
	return radtan_distort(p_d, p_x);
}

bool radtan_undistort(const Radtan &p_d, const glm::dvec2 &p_distorted, glm::dvec2 *r_undistorted) {
	const double scale = 1.0 + std::hypot(p_distorted.x, p_distorted.y);
	glm::dvec2 x = p_distorted;
	double j[4];
	glm::dvec2 residual = radtan_distort(p_d, x, j) - p_distorted;
	double error = std::hypot(residual.x, residual.y);
	for (int iteration = 0; iteration < 50 && error > 1e-16 * scale; iteration++) {
		const double det = j[0] * j[3] - j[1] * j[2];
		if (!(std::abs(det) > 1e-300)) {
			break;
		}
		glm::dvec2 step = { (j[3] * residual.x - j[1] * residual.y) / det, (-j[2] * residual.x + j[0] * residual.y) / det };
		// Halve a step that makes things worse: far from the centre a full Newton step can
		// overshoot into the fold of a strong barrel distortion.
		bool improved = false;
		for (int halving = 0; halving < 40 && !improved; halving++) {
			double candidate_j[4];
			const glm::dvec2 candidate = x - step;
			const glm::dvec2 candidate_residual = radtan_distort(p_d, candidate, candidate_j) - p_distorted;
			const double candidate_error = std::hypot(candidate_residual.x, candidate_residual.y);
			if (candidate_error < error) {
				x = candidate;
				residual = candidate_residual;
				error = candidate_error;
				for (int k = 0; k < 4; k++) {
					j[k] = candidate_j[k];
				}
				improved = true;
			}
			step *= 0.5;
		}
		if (!improved) {
			break; // at the floor of double precision
		}
	}
	*r_undistorted = x;
	return std::isfinite(error) && error <= 1e-12 * scale;
}

} // namespace roomprobe
