#include "prt_transfer.h"

#include <io/embree_scene.h>
#include <math/hash.h>

#include <glm/geometric.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>

namespace roomprobe {

namespace {

double unit_from_bits(uint64_t p_bits) {
	return double(p_bits >> 11) * (1.0 / 9007199254740992.0); // [0, 1)
}

// An orthonormal frame around p_n (Frisvad's, with Duff et al.'s fix for n.z < 0).
void frame_around(const glm::dvec3 &p_n, glm::dvec3 *r_t, glm::dvec3 *r_b) {
	const double sign = std::copysign(1.0, p_n.z);
	const double a = -1.0 / (sign + p_n.z);
	const double b = p_n.x * p_n.y * a;
	*r_t = glm::dvec3(1.0 + sign * p_n.x * p_n.x * a, sign * b, -sign * p_n.x);
	*r_b = glm::dvec3(b, sign + p_n.y * p_n.y * a, -p_n.y);
}

void append_mesh(const PrtMesh &p_mesh, std::vector<float> *io_xyz, std::vector<uint32_t> *io_indices) {
	const uint32_t base = uint32_t(io_xyz->size() / 3);
	for (const glm::vec3 &p : p_mesh.positions) {
		io_xyz->insert(io_xyz->end(), { p.x, p.y, p.z });
	}
	for (uint32_t i : p_mesh.indices) {
		io_indices->push_back(base + i);
	}
}

} // namespace

std::string check_prt_mesh(const PrtMesh &p_mesh) {
	if (p_mesh.positions.empty() || p_mesh.indices.empty()) {
		return "the mesh has no triangles";
	}
	if (p_mesh.normals.size() != p_mesh.positions.size()) {
		return "the mesh has " + std::to_string(p_mesh.normals.size()) + " normals for " + std::to_string(p_mesh.positions.size()) + " vertices";
	}
	if (p_mesh.indices.size() % 3 != 0) {
		return "the mesh's index count (" + std::to_string(p_mesh.indices.size()) + ") is not a multiple of 3";
	}
	for (size_t i = 0; i < p_mesh.indices.size(); i++) {
		if (p_mesh.indices[i] >= p_mesh.positions.size()) {
			return "index " + std::to_string(i) + " (" + std::to_string(p_mesh.indices[i]) + ") is beyond the " + std::to_string(p_mesh.positions.size()) + " vertices";
		}
	}
	for (size_t v = 0; v < p_mesh.positions.size(); v++) {
		const glm::vec3 &p = p_mesh.positions[v];
		const glm::vec3 &n = p_mesh.normals[v];
		if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
			return "vertex " + std::to_string(v) + " is not finite";
		}
		if (!(std::abs(glm::length(n) - 1.0f) < 1e-3f)) {
			return "vertex " + std::to_string(v) + "'s normal is not unit length";
		}
	}
	return std::string();
}

void compute_vertex_normals(PrtMesh *io_mesh) {
	std::vector<glm::dvec3> sums(io_mesh->positions.size(), glm::dvec3(0.0));
	for (size_t t = 0; t + 2 < io_mesh->indices.size(); t += 3) {
		const uint32_t a = io_mesh->indices[t], b = io_mesh->indices[t + 1], c = io_mesh->indices[t + 2];
		if (a >= sums.size() || b >= sums.size() || c >= sums.size()) {
			continue;
		}
		const glm::dvec3 pa(io_mesh->positions[a]), pb(io_mesh->positions[b]), pc(io_mesh->positions[c]);
		const glm::dvec3 area_normal = glm::cross(pb - pa, pc - pa); // twice the area, along the normal
		sums[a] += area_normal;
		sums[b] += area_normal;
		sums[c] += area_normal;
	}
	io_mesh->normals.resize(io_mesh->positions.size());
	for (size_t v = 0; v < sums.size(); v++) {
		const double length = glm::length(sums[v]);
		io_mesh->normals[v] = length > 0.0 ? glm::vec3(sums[v] / length) : glm::vec3(0.0f, 1.0f, 0.0f);
	}
}

TransferResult bake_transfer(const PrtMesh &p_mesh, const PrtMesh *p_occluders, const TransferOptions &p_options) {
	TransferResult result;
	const auto start = std::chrono::steady_clock::now();
	std::string problem = check_prt_mesh(p_mesh);
	if (problem.empty() && p_occluders && !p_occluders->positions.empty()) {
		problem = check_prt_mesh(*p_occluders);
		if (!problem.empty()) {
			problem = "occluders: " + problem;
		}
	}
	if (!problem.empty()) {
		result.error = problem;
		return result;
	}
	const int side = std::max(4, int(std::sqrt(double(std::max(p_options.samples_per_vertex, 16)))));
	const int samples = side * side;
	result.samples_per_vertex = samples;

	std::vector<float> xyz;
	std::vector<uint32_t> indices;
	append_mesh(p_mesh, &xyz, &indices);
	if (p_occluders) {
		append_mesh(*p_occluders, &xyz, &indices);
	}
	glm::dvec3 lo(1e300), hi(-1e300);
	for (size_t i = 0; i < xyz.size(); i += 3) {
		lo = glm::min(lo, glm::dvec3(xyz[i], xyz[i + 1], xyz[i + 2]));
		hi = glm::max(hi, glm::dvec3(xyz[i], xyz[i + 1], xyz[i + 2]));
	}
	const double offset = std::max(p_options.ray_offset, 0.0) * glm::length(hi - lo);
	EmbreeTriangleScene scene;
	problem = scene.build(xyz, indices, true);
	if (!problem.empty()) {
		result.error = problem;
		return result;
	}

	const size_t count = p_mesh.vertex_count();
	result.transfer.assign(count, TransferVector{});
	std::atomic<size_t> done{ 0 };
	const double weight = std::numbers::pi / double(samples); // cosine-weighted: pdf = cos / pi
	tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t> &p_range) {
		for (size_t v = p_range.begin(); v < p_range.end(); v++) {
			const glm::dvec3 n = glm::normalize(glm::dvec3(p_mesh.normals[v]));
			glm::dvec3 t, b;
			frame_around(n, &t, &b);
			const glm::dvec3 origin = glm::dvec3(p_mesh.positions[v]) + n * offset;
			std::array<double, SH_COEFFICIENTS> sum{};
			for (int cell = 0; cell < samples; cell++) {
				const uint64_t bits = splitmix64(splitmix64(p_options.seed ^ (uint64_t(v) << 20)) + uint64_t(cell));
				const double u1 = (double(cell / side) + unit_from_bits(bits)) / side;
				const double u2 = (double(cell % side) + unit_from_bits(splitmix64(bits))) / side;
				const double r = std::sqrt(u1), phi = 2.0 * std::numbers::pi * u2;
				const glm::dvec3 w = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1.0 - u1)) * n;
				if (scene.occluded(origin, w, 0.0, 1e30)) {
					continue;
				}
				const std::array<double, SH_COEFFICIENTS> y = sh_basis(w);
				for (int i = 0; i < SH_COEFFICIENTS; i++) {
					sum[size_t(i)] += y[size_t(i)];
				}
			}
			for (int i = 0; i < SH_COEFFICIENTS; i++) {
				result.transfer[v][size_t(i)] = float(sum[size_t(i)] * weight);
			}
			const size_t finished = ++done;
			if (p_options.progress && (finished % 256 == 0 || finished == count)) {
				p_options.progress(finished, count);
			}
		}
	});
	result.rays = uint64_t(count) * uint64_t(samples);
	result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	return result;
}

TransferVector unshadowed_transfer(const glm::dvec3 &p_normal) {
	const std::array<double, SH_COEFFICIENTS> y = sh_basis(p_normal);
	TransferVector t{};
	for (int l = 0; l < SH_BANDS; l++) {
		for (int m = -l; m <= l; m++) {
			const int i = sh_index(l, m);
			t[size_t(i)] = float(sh_cosine_lobe_factor(l) * y[size_t(i)]);
		}
	}
	return t;
}

glm::dvec3 transfer_irradiance(const TransferVector &p_transfer, const ShCoefficients &p_radiance) {
	glm::dvec3 e(0.0);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		e += double(p_transfer[size_t(i)]) * p_radiance[size_t(i)];
	}
	return e;
}

uint64_t transfer_cache_key(const PrtMesh &p_mesh, const PrtMesh *p_occluders, const TransferOptions &p_options) {
	uint64_t hash = 0xcbf29ce484222325ULL;
	const auto feed = [&hash](const void *p_data, size_t p_bytes) {
		const unsigned char *bytes = static_cast<const unsigned char *>(p_data);
		for (size_t i = 0; i < p_bytes; i++) {
			hash = (hash ^ bytes[i]) * 0x100000001b3ULL;
		}
	};
	for (const PrtMesh *mesh : { &p_mesh, p_occluders }) {
		if (!mesh) {
			continue;
		}
		feed(mesh->positions.data(), mesh->positions.size() * sizeof(glm::vec3));
		feed(mesh->normals.data(), mesh->normals.size() * sizeof(glm::vec3));
		feed(mesh->indices.data(), mesh->indices.size() * sizeof(uint32_t));
	}
	feed(&p_options.samples_per_vertex, sizeof(p_options.samples_per_vertex));
	feed(&p_options.seed, sizeof(p_options.seed));
	feed(&p_options.ray_offset, sizeof(p_options.ray_offset));
	return hash;
}

} // namespace roomprobe
