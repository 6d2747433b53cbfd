#include "contact_shadow.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace roomprobe {

namespace {

double luminance(const glm::dvec3 &p_rgb) {
	return 0.2126 * p_rgb.x + 0.7152 * p_rgb.y + 0.0722 * p_rgb.z;
}

} // namespace

ShadowCatcher bake_shadow_catcher(const PrtMesh &p_object, const glm::dvec3 &p_centre, const glm::dvec3 &p_normal, double p_half_size_m, int p_cells,
		const TransferOptions &p_options) {
	ShadowCatcher catcher;
	if (!(p_half_size_m > 0.0) || !std::isfinite(p_half_size_m) || p_cells < 1 || p_cells > 1024) {
		catcher.error = "the shadow catcher needs a positive size and 1 to 1024 cells a side";
		return catcher;
	}
	const double length = glm::length(p_normal);
	if (!(length > 0.0) || !std::isfinite(length)) {
		catcher.error = "the supporting plane's normal is zero or not finite";
		return catcher;
	}
	const glm::dvec3 n = p_normal / length;
	// Two axes in the plane.
	const glm::dvec3 helper = std::abs(n.y) < 0.9 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(1.0, 0.0, 0.0);
	const glm::dvec3 u = glm::normalize(glm::cross(helper, n));
	const glm::dvec3 v = glm::cross(n, u);
	PrtMesh &plane = catcher.plane;
	for (int j = 0; j <= p_cells; j++) {
		for (int i = 0; i <= p_cells; i++) {
			const double a = (2.0 * i / p_cells - 1.0) * p_half_size_m, b = (2.0 * j / p_cells - 1.0) * p_half_size_m;
			plane.positions.push_back(glm::vec3(p_centre + a * u + b * v));
			plane.normals.push_back(glm::vec3(n));
		}
	}
	const uint32_t row = uint32_t(p_cells + 1);
	for (int j = 0; j < p_cells; j++) {
		for (int i = 0; i < p_cells; i++) {
			const uint32_t k = uint32_t(j) * row + uint32_t(i);
			// Counter-clockwise about n: u then v.
			plane.indices.insert(plane.indices.end(), { k, k + 1, k + row, k + 1, k + row + 1, k + row });
		}
	}
	// The plane is the mesh that gets a transfer, the object the occluder (the plane does not
	// shadow itself: it is flat).
	TransferResult baked = bake_transfer(plane, &p_object, p_options);
	if (!baked.error.empty()) {
		catcher.error = baked.error;
		return catcher;
	}
	catcher.transfer = std::move(baked.transfer);
	return catcher;
}

double shadow_ratio(const TransferVector &p_transfer, const glm::dvec3 &p_normal, const ShCoefficients &p_radiance) {
	const double free = luminance(transfer_irradiance(unshadowed_transfer(glm::normalize(p_normal)), p_radiance));
	if (!(free > 1e-12)) {
		return 1.0;
	}
	return std::clamp(luminance(transfer_irradiance(p_transfer, p_radiance)) / free, 0.0, 1.0);
}

} // namespace roomprobe
