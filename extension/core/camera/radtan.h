#pragma once
// OpenCV's radial-tangential distortion on normalized coordinates, shared by the pinhole and the
// unified omnidirectional models (the latter with k3 = 0). Internal to camera/.

#include <glm/vec2.hpp>

namespace roomprobe {

struct Radtan {
	double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
};

// Distorts undistorted normalized coordinates, exactly as cv::projectPoints does.
glm::dvec2 radtan_distort(const Radtan &p_d, const glm::dvec2 &p_x);
// Distorts and gives the 2x2 Jacobian d(distorted)/d(undistorted), row-major in r_jacobian.
glm::dvec2 radtan_distort(const Radtan &p_d, const glm::dvec2 &p_x, double r_jacobian[4]);
// Inverts radtan_distort by Newton's method from the distorted point (quadratic convergence, so
// round trips reach machine precision where cv::undistortPoints' fixed-point iteration would
// need many more steps). Returns false when it did not converge (|residual| > 1e-12).
bool radtan_undistort(const Radtan &p_d, const glm::dvec2 &p_distorted, glm::dvec2 *r_undistorted);

} // namespace roomprobe
