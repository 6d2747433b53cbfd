#pragma once
// Diffuse shadowed precomputed radiance transfer (paper §4.8, after Sloan, Kautz and Snyder
// 2002), 5 SH bands: for each vertex p with normal n,
//
//   T_i(p) = integral over the sphere of y_i(w) V(p, w) max(0, n . w) dw,   i = 0..24,
//
// with y_i the core's SH basis (envmap/spherical_harmonics.h) and V the visibility of the
// distant environment from p (0 where the mesh itself, or an occluder, is in the way). A vertex
// of albedo a in an environment of SH radiance L_i then leaves
//
//   radiance = a / pi * sum_i L_i T_i
//
// (the PRT shader dots the transfer with the probe's SH). Without occlusion T_i = A_l y_i(n), the
// clamped cosine in SH (convolve_cosine_lobe's factors).
//
// The integral is estimated with cosine-weighted directions, stratified over a square grid of
// samples_per_vertex cells, each jittered by a hash of (vertex, cell) (deterministic), and
// visibility by Embree any-hit rays from the vertex, nudged off the surface along its normal.

#include <envmap/spherical_harmonics.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace roomprobe {

// A triangle mesh with one normal per vertex (plain data).
struct PrtMesh {
	std::vector<glm::vec3> positions; // metres (any unit: the transfer is unitless)
	std::vector<glm::vec3> normals; // unit, one per position
	std::vector<uint32_t> indices; // 3 per triangle, counter-clockwise seen from outside

	size_t vertex_count() const { return positions.size(); }
	size_t triangle_count() const { return indices.size() / 3; }
};

// "" or what is wrong: sizes that disagree, an index out of range, a non-finite position, a
// normal that is not unit length.
std::string check_prt_mesh(const PrtMesh &p_mesh);

// Per-vertex normals from the triangles (area-weighted), for meshes that come without.
void compute_vertex_normals(PrtMesh *io_mesh);

using TransferVector = std::array<float, SH_COEFFICIENTS>;

struct TransferOptions {
	// Rounded down to a square (stratification), at least 16. The error converges as 1 / samples:
	// on a lone sphere 1.9 % of the lobe's norm at 1024, 0.43 % at 4096 (tests/core/test_prt_transfer.cpp).
	int samples_per_vertex = 4096;
	// Rays start this far off the surface along the normal, as a fraction of the mesh's bounding
	// box diagonal (a ray must not hit the triangle it leaves).
	double ray_offset = 1e-4;
	uint64_t seed = 1;
	std::function<void(size_t p_done, size_t p_total)> progress; // vertices; may be called from any thread
};

struct TransferResult {
	std::string error;
	std::vector<TransferVector> transfer; // one per vertex
	int samples_per_vertex = 0; // as used
	double seconds = 0.0;
	uint64_t rays = 0;
};

// The transfer of every vertex of p_mesh, self-shadowed, and shadowed by p_occluders too when
// given (e.g. the plane an object stands on: it casts shadows, it gets no transfer).
TransferResult bake_transfer(const PrtMesh &p_mesh, const PrtMesh *p_occluders, const TransferOptions &p_options = TransferOptions());

// The transfer without any occlusion, A_l y_i(n): what bake_transfer approaches for a convex mesh.
TransferVector unshadowed_transfer(const glm::dvec3 &p_normal);

// sum_i L_i T_i: the irradiance a vertex receives (divide by pi, times albedo, for its radiance).
glm::dvec3 transfer_irradiance(const TransferVector &p_transfer, const ShCoefficients &p_radiance);

// A 64-bit hash (FNV-1a) of the mesh's positions, normals and indices and of the bake's sample
// count and seed: a cached transfer is reused only while this matches.
uint64_t transfer_cache_key(const PrtMesh &p_mesh, const PrtMesh *p_occluders, const TransferOptions &p_options);

} // namespace roomprobe
