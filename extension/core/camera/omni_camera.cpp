#include "omni_camera.h"

#include "radtan.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace roomprobe {

namespace {

Radtan omni_distortion(const OmniParams &p_params) {
	return { p_params.k1, p_params.k2, p_params.p1, p_params.p2, 0.0 };
}

// cos of max_angle_deg, or -2 (below any cosine) when there is no limit.
double min_cos_angle(const OmniParams &p_params) {
	return p_params.max_angle_deg > 0.0 ? std::cos(p_params.max_angle_deg * std::numbers::pi / 180.0) : -2.0;
}

bool inside_circle(const OmniParams &p_params, const glm::dvec2 &p_pixel) {
	if (p_params.circle_radius <= 0.0) {
		return true;
	}
	const double dx = p_pixel.x - p_params.circle_cx, dy = p_pixel.y - p_params.circle_cy;
	return dx * dx + dy * dy <= p_params.circle_radius * p_params.circle_radius;
}

} // namespace

bool project_omni(const OmniParams &p_params, const glm::dvec3 &p_point, glm::dvec2 *r_pixel) {
	const double norm = glm::length(p_point);
	if (!(norm > 0.0) || !std::isfinite(norm)) {
		return false;
	}
	const glm::dvec3 s = p_point / norm; // on the unit sphere
	if (s.z < min_cos_angle(p_params)) {
		return false;
	}
	const double xi = p_params.xi;
	const double denominator = s.z + xi;
	// The model has no projection where s.z <= -xi; for xi > 1 the image also folds back where
	// 1 + xi * s.z <= 0 (the radius shrinks again), and there the pixel would not give this ray
	// back, so it counts as unseen too.
	if (!(denominator > 0.0) || (xi > 1.0 && !(1.0 + xi * s.z > 0.0))) {
		return false;
	}
	const glm::dvec2 distorted = radtan_distort(omni_distortion(p_params), glm::dvec2(s.x / denominator, s.y / denominator));
	const glm::dvec2 pixel = { p_params.fx * distorted.x + p_params.skew * distorted.y + p_params.cx, p_params.fy * distorted.y + p_params.cy };
	// A ray that lands outside the image circle is not seen through the lens.
	if (!inside_circle(p_params, pixel)) {
		return false;
	}
	*r_pixel = pixel;
	return true;
}

bool unproject_omni(const OmniParams &p_params, const glm::dvec2 &p_pixel, glm::dvec3 *r_ray) {
	// The circle, not the image's edges (omni_pixel_valid's business): a caller may ask for the
	// rays of pixels just off the sensor, e.g. for a filter's footprint.
	if (!std::isfinite(p_pixel.x) || !std::isfinite(p_pixel.y) || !inside_circle(p_params, p_pixel)) {
		return false;
	}
	const double yd = (p_pixel.y - p_params.cy) / p_params.fy;
	const double xd = (p_pixel.x - p_params.cx - p_params.skew * yd) / p_params.fx;
	glm::dvec2 x;
	if (!radtan_undistort(omni_distortion(p_params), glm::dvec2(xd, yd), &x)) {
		return false;
	}
	// Closed-form lift of the normalized point onto the unit sphere (Mei): the root with
	// 1 + xi * z >= 0, the branch project_omni accepts.
	const double xi = p_params.xi;
	const double r2 = x.x * x.x + x.y * x.y;
	const double discriminant = 1.0 + (1.0 - xi * xi) * r2;
	if (!(discriminant >= 0.0)) {
		return false; // beyond the fold of a xi > 1 model: no ray maps here
	}
	const double eta = (xi + std::sqrt(discriminant)) / (r2 + 1.0);
	if (!(eta > 0.0)) {
		return false;
	}
	const glm::dvec3 ray = glm::normalize(glm::dvec3(eta * x.x, eta * x.y, eta - xi));
	// A little slack so that project_omni's own pixels at exactly max_angle_deg come back.
	if (ray.z < min_cos_angle(p_params) - 1e-12) {
		return false;
	}
	*r_ray = ray;
	return true;
}

bool omni_pixel_valid(const OmniParams &p_params, const glm::dvec2 &p_pixel) {
	if (!std::isfinite(p_pixel.x) || !std::isfinite(p_pixel.y)) {
		return false;
	}
	// Pixel centres are integers, so the image spans [-0.5, size - 0.5] (camera_params.h); a size
	// of 0 sets no bound.
	if (p_params.width > 0 && (p_pixel.x < -0.5 || p_pixel.x > p_params.width - 0.5)) {
		return false;
	}
	if (p_params.height > 0 && (p_pixel.y < -0.5 || p_pixel.y > p_params.height - 0.5)) {
		return false;
	}
	return inside_circle(p_params, p_pixel);
}

} // namespace roomprobe
