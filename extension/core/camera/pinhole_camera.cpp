#include "pinhole_camera.h"

#include "radtan.h"

#include <cmath>
#include <numbers>

namespace roomprobe {

namespace {

Radtan pinhole_distortion(const PinholeParams &p_params) {
	return { p_params.k1, p_params.k2, p_params.p1, p_params.p2, p_params.k3 };
}

} // namespace

bool project_pinhole(const PinholeParams &p_params, const glm::dvec3 &p_point, glm::dvec2 *r_pixel) {
	// Not '<= 0' alone: NaN must fail too.
	if (!(p_point.z > 0.0)) {
		return false;
	}
	const glm::dvec2 distorted = radtan_distort(pinhole_distortion(p_params), glm::dvec2(p_point.x / p_point.z, p_point.y / p_point.z));
	*r_pixel = { p_params.fx * distorted.x + p_params.cx, p_params.fy * distorted.y + p_params.cy };
	return true;
}

glm::dvec3 unproject_pinhole(const PinholeParams &p_params, const glm::dvec2 &p_pixel) {
	const glm::dvec2 distorted = { (p_pixel.x - p_params.cx) / p_params.fx, (p_pixel.y - p_params.cy) / p_params.fy };
	glm::dvec2 undistorted;
	// Where Newton does not converge (far outside a strongly distorted image) the best estimate is
	// still the most useful ray to return.
	radtan_undistort(pinhole_distortion(p_params), distorted, &undistorted);
	return { undistorted.x, undistorted.y, 1.0 };
}

PinholeIntrinsics pinhole_intrinsics(const PinholeParams &p_params) {
	return { float(p_params.fx), float(p_params.fy), float(p_params.cx), float(p_params.cy), p_params.width, p_params.height };
}

bool has_pinhole_distortion(const PinholeParams &p_params) {
	return p_params.k1 != 0.0 || p_params.k2 != 0.0 || p_params.p1 != 0.0 || p_params.p2 != 0.0 || p_params.k3 != 0.0;
}

double pinhole_vertical_fov_degrees(const PinholeParams &p_params) {
	return p_params.fy > 0.0 && p_params.height > 0 ? 2.0 * std::atan(0.5 * p_params.height / p_params.fy) * 180.0 / std::numbers::pi : 0.0;
}

} // namespace roomprobe
