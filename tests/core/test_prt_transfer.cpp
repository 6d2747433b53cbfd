// Diffuse shadowed PRT transfer (prt/prt_transfer.h, paper §4.8): a lone sphere's transfer is the
// clamped cosine in SH; a sphere resting on a plane, and the inside of a cup, match a brute-force
// Monte Carlo reference (uniform directions over the whole sphere, Embree's nearest-hit rays: a
// different estimator and a different query from the bake's). The contact shadow's ratio
// (prt/contact_shadow.h) under a sphere against the analytic visible fraction of the sky.

#include "prt_test_meshes.h"

#include "io/embree_scene.h"
#include "prt/contact_shadow.h"
#include "prt/prt_transfer.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace roomprobe;

namespace {

// An n x n grid of quads in the plane y = p_y, over [x0, x1] x [z0, z1], normal p_up (+Y or -Y).
void add_grid(PrtMesh *io_mesh, float p_x0, float p_x1, float p_z0, float p_z1, float p_y, int p_n, float p_up) {
	const uint32_t base = uint32_t(io_mesh->positions.size());
	for (int j = 0; j <= p_n; j++) {
		for (int i = 0; i <= p_n; i++) {
			io_mesh->positions.emplace_back(p_x0 + (p_x1 - p_x0) * i / p_n, p_y, p_z0 + (p_z1 - p_z0) * j / p_n);
			io_mesh->normals.emplace_back(0.0f, p_up, 0.0f);
		}
	}
	for (int j = 0; j < p_n; j++) {
		for (int i = 0; i < p_n; i++) {
			const uint32_t a = base + uint32_t(j * (p_n + 1) + i), b = a + 1, c = a + uint32_t(p_n + 1), d = c + 1;
			io_mesh->indices.insert(io_mesh->indices.end(), { a, c, b, b, c, d });
		}
	}
}

// A wall quad from corner p_a to p_b (horizontal), p_height high, facing p_normal.
void add_wall(PrtMesh *io_mesh, const glm::vec3 &p_a, const glm::vec3 &p_b, float p_height, const glm::vec3 &p_normal) {
	const uint32_t base = uint32_t(io_mesh->positions.size());
	for (const glm::vec3 &p : { p_a, p_b, p_a + glm::vec3(0, p_height, 0), p_b + glm::vec3(0, p_height, 0) }) {
		io_mesh->positions.push_back(p);
		io_mesh->normals.push_back(p_normal);
	}
	io_mesh->indices.insert(io_mesh->indices.end(), { base, base + 1, base + 2, base + 1, base + 3, base + 2 });
}

// Brute force: N directions uniform over the whole sphere, visibility by nearest-hit rays.
TransferVector reference_transfer(const EmbreeTriangleScene &p_scene, const glm::dvec3 &p_point, const glm::dvec3 &p_normal, int p_samples, double p_offset) {
	std::mt19937_64 random(12345);
	std::uniform_real_distribution<double> unit(0.0, 1.0);
	std::array<double, SH_COEFFICIENTS> sum{};
	const glm::dvec3 origin = p_point + p_normal * p_offset;
	for (int s = 0; s < p_samples; s++) {
		const double z = 1.0 - 2.0 * unit(random), phi = 2.0 * std::numbers::pi * unit(random);
		const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
		const glm::dvec3 w(r * std::cos(phi), r * std::sin(phi), z);
		const double cosine = glm::dot(w, p_normal);
		EmbreeTriangleScene::RayHit hit;
		if (cosine <= 0.0 || p_scene.intersect(origin, w, 0.0, 1e30, &hit)) {
			continue;
		}
		const std::array<double, SH_COEFFICIENTS> y = sh_basis(w);
		for (int i = 0; i < SH_COEFFICIENTS; i++) {
			sum[size_t(i)] += y[size_t(i)] * cosine;
		}
	}
	TransferVector t{};
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		t[size_t(i)] = float(sum[size_t(i)] * 4.0 * std::numbers::pi / p_samples);
	}
	return t;
}

double norm(const TransferVector &p_t) {
	double s = 0.0;
	for (float v : p_t) {
		s += double(v) * v;
	}
	return std::sqrt(s);
}

double distance(const TransferVector &p_a, const TransferVector &p_b) {
	double s = 0.0;
	for (size_t i = 0; i < p_a.size(); i++) {
		s += (double(p_a[i]) - p_b[i]) * (double(p_a[i]) - p_b[i]);
	}
	return std::sqrt(s);
}

void build_scene(const std::vector<const PrtMesh *> &p_meshes, EmbreeTriangleScene *r_scene) {
	std::vector<float> xyz;
	std::vector<uint32_t> indices;
	for (const PrtMesh *mesh : p_meshes) {
		const uint32_t base = uint32_t(xyz.size() / 3);
		for (const glm::vec3 &p : mesh->positions) {
			xyz.insert(xyz.end(), { p.x, p.y, p.z });
		}
		for (uint32_t i : mesh->indices) {
			indices.push_back(base + i);
		}
	}
	REQUIRE(r_scene->build(xyz, indices, true) == "");
}

} // namespace

TEST_CASE("prt transfer: a lone sphere's transfer is the clamped cosine in SH") {
	const PrtMesh sphere = uv_sphere(glm::vec3(0.0f), 0.5f, 12, 24);
	REQUIRE(check_prt_mesh(sphere) == "");
	TransferOptions options;
	options.samples_per_vertex = 4096;
	const TransferResult baked = bake_transfer(sphere, nullptr, options);
	REQUIRE_MESSAGE(baked.error.empty(), baked.error);
	CHECK(baked.samples_per_vertex == 4096);
	double worst = 0.0;
	for (size_t v = 0; v < sphere.vertex_count(); v++) {
		const TransferVector exact = unshadowed_transfer(glm::dvec3(sphere.normals[v]));
		worst = std::max(worst, distance(baked.transfer[v], exact) / norm(exact));
		// Band 0 is exact with cosine-weighted directions (its integrand is the pdf's shape).
		CHECK(baked.transfer[v][0] == doctest::Approx(exact[0]).epsilon(1e-5));
	}
	MESSAGE("lone sphere: " << sphere.vertex_count() << " vertices, worst relative error " << 100.0 * worst << " % with " << baked.samples_per_vertex
							<< " samples; " << baked.seconds * 1e6 / double(sphere.vertex_count()) << " us a vertex");
	// The stratified estimate of bands 1-4 converges as 1 / samples (measured: 1.9 % at 1024,
	// 0.43 % at 4096): 1 % of the lobe's norm at the default 4096.
	CHECK(worst < 0.01);
}

// Errors are measured against the lobe's full scale (the unshadowed transfer's norm): 1 % of
// what an unoccluded vertex receives, whatever the fraction of sky the vertex sees.
TEST_CASE("prt transfer: a sphere resting on a plane matches a brute-force reference within 1 % of the unshadowed lobe") {
	const PrtMesh sphere = uv_sphere(glm::vec3(0.0f, 0.5f, 0.0f), 0.5f, 16, 32);
	PrtMesh plane;
	add_grid(&plane, -20.0f, 20.0f, -20.0f, 20.0f, 0.0f, 1, 1.0f);
	TransferOptions options;
	options.samples_per_vertex = 4096;
	const TransferResult baked = bake_transfer(sphere, &plane, options);
	REQUIRE_MESSAGE(baked.error.empty(), baked.error);
	EmbreeTriangleScene scene;
	build_scene({ &sphere, &plane }, &scene);
	const double offset = 1e-4 * std::sqrt(40.0 * 40.0 * 2.0 + 1.0);
	// Vertices from the equator down to just above the contact (ring 16 is the bottom pole).
	int checked = 0;
	for (int ring : { 8, 10, 12, 14, 15 }) {
		const size_t v = size_t(ring) * 33 + 5;
		const TransferVector reference = reference_transfer(scene, glm::dvec3(sphere.positions[v]), glm::dvec3(sphere.normals[v]), 1 << 19, offset);
		const TransferVector unshadowed = unshadowed_transfer(glm::dvec3(sphere.normals[v]));
		const double error = distance(baked.transfer[v], reference) / norm(unshadowed);
		CAPTURE(ring);
		MESSAGE("ring " << ring << ": band-0 transfer " << baked.transfer[v][0] << " (reference " << reference[0] << ", unshadowed " << unshadowed[0]
						<< "), relative error " << 100.0 * error << " %");
		CHECK(error < 0.01);
		if (ring >= 12) {
			CHECK(baked.transfer[v][0] < 0.9f * unshadowed[0]); // the plane shadows it
		}
		checked++;
	}
	CHECK(checked == 5);
}

TEST_CASE("prt transfer: the inside of a cup is darker than the ground outside it, by the reference's amount") {
	// A 1 m square cup, 0.6 m deep, open at the top, on a ground plane; walls one-sided (facing in),
	// which rays hit from both sides.
	PrtMesh mesh;
	add_grid(&mesh, -0.5f, 0.5f, -0.5f, 0.5f, 0.0f, 4, 1.0f); // the cup's floor; vertex 12 is its centre
	add_grid(&mesh, 1.5f, 3.5f, -1.0f, 1.0f, 0.0f, 2, 1.0f); // ground outside; vertex 25 + 4 is its centre (2.5, 0, 0)
	const float h = 0.6f;
	add_wall(&mesh, { -0.5f, 0, -0.5f }, { 0.5f, 0, -0.5f }, h, { 0, 0, 1 });
	add_wall(&mesh, { 0.5f, 0, 0.5f }, { -0.5f, 0, 0.5f }, h, { 0, 0, -1 });
	add_wall(&mesh, { -0.5f, 0, 0.5f }, { -0.5f, 0, -0.5f }, h, { 1, 0, 0 });
	add_wall(&mesh, { 0.5f, 0, -0.5f }, { 0.5f, 0, 0.5f }, h, { -1, 0, 0 });
	REQUIRE(check_prt_mesh(mesh) == "");
	TransferOptions options;
	options.samples_per_vertex = 4096;
	const TransferResult baked = bake_transfer(mesh, nullptr, options);
	REQUIRE_MESSAGE(baked.error.empty(), baked.error);
	const size_t inside = 12, outside = 25 + 4;
	REQUIRE(mesh.positions[inside] == glm::vec3(0.0f));
	REQUIRE(mesh.positions[outside] == glm::vec3(2.5f, 0.0f, 0.0f));
	EmbreeTriangleScene scene;
	build_scene({ &mesh }, &scene);
	glm::dvec3 lo(1e30), hi(-1e30);
	for (const glm::vec3 &p : mesh.positions) {
		lo = glm::min(lo, glm::dvec3(p));
		hi = glm::max(hi, glm::dvec3(p));
	}
	const double offset = 1e-4 * glm::length(hi - lo);
	const TransferVector ref_in = reference_transfer(scene, glm::dvec3(mesh.positions[inside]), glm::dvec3(0, 1, 0), 1 << 19, offset);
	const TransferVector ref_out = reference_transfer(scene, glm::dvec3(mesh.positions[outside]), glm::dvec3(0, 1, 0), 1 << 19, offset);
	// Under a uniform white sky (L_0 only) the irradiance is T_0 times L_0: the ratio in/out.
	const double ratio = baked.transfer[inside][0] / baked.transfer[outside][0];
	const double ref_ratio = double(ref_in[0]) / ref_out[0];
	MESSAGE("cup: inside/outside irradiance under a uniform sky " << ratio << " (reference " << ref_ratio << ")");
	CHECK(ratio < 0.9);
	CHECK(ratio == doctest::Approx(ref_ratio).epsilon(0.01));
	CHECK(distance(baked.transfer[inside], ref_in) / norm(unshadowed_transfer(glm::dvec3(0, 1, 0))) < 0.01);
}

TEST_CASE("prt transfer: bad meshes are refused with the reason; the cache key follows the mesh and the settings") {
	PrtMesh mesh = uv_sphere(glm::vec3(0.0f), 1.0f, 12, 24);
	PrtMesh broken = mesh;
	broken.indices.push_back(9999);
	CHECK(check_prt_mesh(broken).find("not a multiple of 3") != std::string::npos);
	broken.indices.push_back(0);
	broken.indices.push_back(0);
	CHECK(bake_transfer(broken, nullptr).error.find("beyond the") != std::string::npos);
	PrtMesh no_normals = mesh;
	no_normals.normals.pop_back();
	CHECK(bake_transfer(no_normals, nullptr).error.find("normals for") != std::string::npos);
	PrtMesh nan = mesh;
	nan.positions[3].y = std::nanf("");
	CHECK(check_prt_mesh(nan) == "vertex 3 is not finite");
	CHECK(bake_transfer(PrtMesh(), nullptr).error == "the mesh has no triangles");
	// Normals from the triangles: outward on a sphere wound counter-clockwise.
	PrtMesh renormal = mesh;
	compute_vertex_normals(&renormal);
	for (size_t v = 0; v < mesh.vertex_count(); v++) {
		CAPTURE(v);
		// (At a pole or the seam a vertex has the triangles of one side only: a few degrees off.)
		CHECK(glm::dot(renormal.normals[v], mesh.normals[v]) > 0.9f);
	}
	const TransferOptions options;
	const uint64_t key = transfer_cache_key(mesh, nullptr, options);
	CHECK(transfer_cache_key(mesh, nullptr, options) == key);
	PrtMesh moved = mesh;
	moved.positions[0].x += 1e-3f;
	CHECK(transfer_cache_key(moved, nullptr, options) != key);
	TransferOptions more = options;
	more.samples_per_vertex *= 2;
	CHECK(transfer_cache_key(mesh, nullptr, more) != key);
}

TEST_CASE("contact shadow: under a sphere on a plane the ratio is the analytic fraction of the sky left visible") {
	// A sphere of radius R resting on the plane y = 0. From a plane point at distance d from the
	// contact, the sphere (centre at distance D = sqrt(d^2 + R^2), seen at cos(theta) = R / D from
	// the normal, entirely above the horizon) has the form factor (R / D)^2 cos(theta) = (R / D)^3:
	// under a uniform sky the plane keeps 1 - (R / D)^3 of its irradiance.
	const float radius = 0.5f;
	const PrtMesh sphere = uv_sphere(glm::vec3(0.0f, radius, 0.0f), radius, 48, 96);
	const ShadowCatcher catcher = bake_shadow_catcher(sphere, glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), 2.0, 16);
	REQUIRE_MESSAGE(catcher.error.empty(), catcher.error);
	REQUIRE(catcher.transfer.size() == 17 * 17);
	ShCoefficients uniform{};
	uniform[0] = glm::dvec3(std::sqrt(4.0 * std::numbers::pi)); // radiance 1 from every direction
	for (int i : { 9, 10, 12, 16 }) {
		const size_t v = size_t(8) * 17 + size_t(i); // along one axis through the contact
		const double d = glm::length(glm::dvec3(catcher.plane.positions[v]));
		const double expected = 1.0 - std::pow(radius / std::hypot(d, double(radius)), 3.0);
		const double ratio = shadow_ratio(catcher.transfer[v], glm::dvec3(0.0, 1.0, 0.0), uniform);
		CAPTURE(d);
		MESSAGE("d = " << d / radius << " R: ratio " << ratio << ", analytic " << expected);
		// The bake's error (0.4 % of the lobe at 4096 samples) and the 96-segment sphere's facets.
		CHECK(std::abs(ratio - expected) < 0.01);
	}
	// Far from the object nothing is shadowed; a light from straight above darkens the point under
	// the sphere more than a uniform sky does (its direction is the one the sphere blocks).
	const size_t corner = 0;
	CHECK(shadow_ratio(catcher.transfer[corner], glm::dvec3(0.0, 1.0, 0.0), uniform) > 0.99);
	ShCoefficients above{};
	const std::array<double, SH_COEFFICIENTS> y = sh_basis(glm::dvec3(0.0, 1.0, 0.0));
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		above[size_t(i)] = glm::dvec3(y[size_t(i)]); // a band-limited spot straight up
	}
	const size_t near = size_t(8) * 17 + 9;
	CHECK(shadow_ratio(catcher.transfer[near], glm::dvec3(0.0, 1.0, 0.0), above) < shadow_ratio(catcher.transfer[near], glm::dvec3(0.0, 1.0, 0.0), uniform));
	// Bad settings are refused with the reason.
	CHECK(bake_shadow_catcher(sphere, glm::dvec3(0.0), glm::dvec3(0.0), 1.0, 4).error.find("normal is zero") != std::string::npos);
	CHECK(bake_shadow_catcher(sphere, glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), -1.0, 4).error.find("positive size") != std::string::npos);
}
