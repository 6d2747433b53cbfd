#pragma once
// Meshes for the PRT and virtual-object tests.

#include "prt/prt_transfer.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace roomprobe {

// A UV sphere: rings x segments quads, poles shared.
inline PrtMesh uv_sphere(const glm::vec3 &p_centre, float p_radius, int p_rings, int p_segments) {
	PrtMesh mesh;
	for (int r = 0; r <= p_rings; r++) {
		const double theta = std::numbers::pi * r / p_rings;
		for (int s = 0; s <= p_segments; s++) {
			const double phi = 2.0 * std::numbers::pi * s / p_segments;
			const glm::vec3 n(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)), float(std::sin(theta) * std::sin(phi)));
			mesh.positions.push_back(p_centre + p_radius * n);
			mesh.normals.push_back(glm::normalize(n));
		}
	}
	const uint32_t stride = uint32_t(p_segments + 1);
	for (int r = 0; r < p_rings; r++) {
		for (int s = 0; s < p_segments; s++) {
			const uint32_t a = uint32_t(r) * stride + uint32_t(s), b = a + 1, c = a + stride, d = c + 1;
			mesh.indices.insert(mesh.indices.end(), { a, b, c, b, d, c }); // counter-clockwise from outside
		}
	}
	return mesh;
}

} // namespace roomprobe
