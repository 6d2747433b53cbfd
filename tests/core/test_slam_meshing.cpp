// Marching cubes over the TSDF (paper §4.2's colour model as a mesh), against an analytic sphere,
// and its incremental re-meshing of changed blocks.

#include <io/opencv.h>

#include "slam/marching_cubes.h"
#include "slam_test_scenes.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <bit>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

using namespace roomprobe;
using namespace slam_test;

namespace {

const glm::dvec3 CENTRE(0.0, 0.0, 0.0);
constexpr double RADIUS = 0.3;

Scene sphere_scene() {
	Scene scene;
	scene.spheres.push_back({ CENTRE, RADIUS });
	return scene;
}

void integrate_view(TsdfVolume *r_volume, const PinholeIntrinsics &p_camera, double p_azimuth_deg, double p_elevation_deg) {
	const Frame f = render(sphere_scene(), p_camera, orbit_pose(CENTRE, 1.0, p_azimuth_deg, p_elevation_deg));
	r_volume->integrate(f.depth, f.rgb, p_camera, f.world_from_camera);
}

bool meshes_equal(const TriangleMesh &p_a, const TriangleMesh &p_b) {
	return p_a.vertices == p_b.vertices && p_a.normals == p_b.normals && p_a.colors == p_b.colors && p_a.indices == p_b.indices;
}

// Vertices welded across blocks (pieces repeat the vertices on their shared faces), to 1e-5 m.
std::vector<uint32_t> welded_indices(const TriangleMesh &p_mesh) {
	std::map<std::tuple<long, long, long>, uint32_t> ids;
	std::vector<uint32_t> id_of(p_mesh.vertices.size());
	for (size_t i = 0; i < p_mesh.vertices.size(); i++) {
		const glm::vec3 &v = p_mesh.vertices[i];
		const auto key = std::make_tuple(std::lround(v.x * 1e5f), std::lround(v.y * 1e5f), std::lround(v.z * 1e5f));
		id_of[i] = ids.emplace(key, uint32_t(ids.size())).first->second;
	}
	std::vector<uint32_t> indices;
	for (uint32_t i : p_mesh.indices) {
		indices.push_back(id_of[i]);
	}
	return indices;
}

// The blocks a change must re-mesh: the changed blocks and the allocated blocks below them
// (whose cubes reach one voxel into them).
// p_volume: a TsdfVolume or a TsdfBlockCopy.
template <typename Blocks>
int expected_remesh(const Blocks &p_volume, const std::vector<glm::ivec3> &p_changed) {
	std::set<std::tuple<int, int, int>> expected;
	for (const glm::ivec3 &b : p_changed) {
		for (int c = 0; c < 8; c++) {
			const glm::ivec3 n = b - glm::ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
			if (p_volume.find_block(n) != nullptr) {
				expected.insert({ n.x, n.y, n.z });
			}
		}
	}
	return int(expected.size());
}

} // namespace

TEST_CASE("marching-cubes table: generated from the cube's topology, consistent") {
	const auto &table = mc_case_table();
	const auto &edges = mc_edge_corners();
	CHECK(table[0].triangle_count == 0);
	CHECK(table[255].triangle_count == 0);
	for (int mask = 1; mask < 255; mask++) {
		const McCase &mc = table[size_t(mask)];
		std::set<int> crossed, used;
		for (int e = 0; e < 12; e++) {
			if (((mask >> edges[size_t(e)][0]) & 1) != ((mask >> edges[size_t(e)][1]) & 1)) {
				crossed.insert(e);
			}
		}
		for (int k = 0; k < 3 * mc.triangle_count; k++) {
			used.insert(mc.edges[size_t(k)]);
		}
		// Every crossed edge gets a vertex and no other edge does.
		CHECK(used == crossed);
		// Loops of n vertices give n - 2 triangles: at most 12 - 2.
		CHECK(mc.triangle_count <= 10);
		if (std::popcount(unsigned(mask)) == 1 || std::popcount(unsigned(mask)) == 7) {
			CHECK(mc.triangle_count == 1); // a corner cut off
		}
	}
	// One inside corner: the triangle faces away from it (its normal by the right-hand rule points
	// to the outside, i.e. towards increasing tsdf).
	for (int corner = 0; corner < 8; corner++) {
		const McCase &mc = table[size_t(1 << corner)];
		glm::vec3 p[3];
		for (int k = 0; k < 3; k++) {
			const auto &e = edges[mc.edges[size_t(k)]];
			const glm::vec3 a(e[0] & 1, (e[0] >> 1) & 1, (e[0] >> 2) & 1), b(e[1] & 1, (e[1] >> 1) & 1, (e[1] >> 2) & 1);
			p[k] = 0.5f * (a + b);
		}
		const glm::vec3 inside(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
		CHECK(glm::dot(glm::cross(p[1] - p[0], p[2] - p[0]), (p[0] + p[1] + p[2]) / 3.0f - inside) > 0.0f);
	}
}

TEST_CASE("mesh of an integrated sphere: on the surface, outward, manifold") {
	const PinholeIntrinsics camera = rig_camera(1); // 320 x 240
	TsdfOptions options;
	TsdfVolume volume(options);
	for (double elevation : { 30.0, -30.0 }) {
		for (int i = 0; i < 8; i++) {
			integrate_view(&volume, camera, 45.0 * i, elevation);
		}
	}
	const TriangleMesh mesh = mesh_volume(volume);
	REQUIRE(mesh.indices.size() >= 3000);
	CHECK(mesh.indices.size() % 3 == 0);
	CHECK(mesh.normals.size() == mesh.vertices.size());
	CHECK(mesh.colors.size() == mesh.vertices.size());
	const float voxel = options.voxel_size_m;
	int on_surface = 0, normal_ok = 0;
	for (size_t i = 0; i < mesh.vertices.size(); i++) {
		const glm::vec3 radial = mesh.vertices[i] - glm::vec3(CENTRE);
		on_surface += std::fabs(glm::length(radial) - float(RADIUS)) <= voxel;
		// The vertex normal is the gradient of the trilinear cell: exact for a plane; a 1 cm cell
		// on a 0.3 m sphere turns by 1 / 30 rad = 2 deg, plus the 5 deg bound of the field
		// (test_slam_tsdf.cpp): 7 deg.
		normal_ok += glm::degrees(std::acos(std::clamp(glm::dot(mesh.normals[i], glm::normalize(radial)), -1.0f, 1.0f))) <= 7.0f;
	}
	MESSAGE(mesh.vertices.size() << " vertices, " << mesh.indices.size() / 3 << " triangles; on surface " << on_surface << ", normals ok " << normal_ok);
	CHECK(on_surface == int(mesh.vertices.size()));
	CHECK(normal_ok >= 0.99 * double(mesh.vertices.size()));
	// Triangles face outwards.
	int outward = 0;
	for (size_t t = 0; t < mesh.indices.size(); t += 3) {
		const glm::vec3 &a = mesh.vertices[mesh.indices[t]], &b = mesh.vertices[mesh.indices[t + 1]], &c = mesh.vertices[mesh.indices[t + 2]];
		outward += glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0f - glm::vec3(CENTRE)) > 0.0f;
	}
	CHECK(outward == int(mesh.indices.size() / 3));
	// Consistently oriented manifold: each directed edge once (across block seams too).
	const std::vector<uint32_t> welded = welded_indices(mesh);
	std::set<std::pair<uint32_t, uint32_t>> directed;
	int repeated = 0;
	for (size_t t = 0; t < welded.size(); t += 3) {
		for (int k = 0; k < 3; k++) {
			repeated += !directed.insert({ welded[t + size_t(k)], welded[t + size_t((k + 1) % 3)] }).second;
		}
	}
	CHECK(repeated == 0);
	// Colours follow the pattern (bound as in test_slam_tsdf.cpp: one voxel of the pattern's
	// gradient plus rounding).
	int color_ok = 0;
	for (size_t i = 0; i < mesh.vertices.size(); i++) {
		const glm::dvec3 expected = pattern_color(glm::dvec3(mesh.vertices[i]));
		const glm::dvec3 got(mesh.colors[i]);
		color_ok += glm::all(glm::lessThanEqual(glm::abs(got - expected), glm::dvec3(PATTERN_MAX_GRADIENT * voxel + 2.0)));
	}
	CHECK(color_ok >= 0.99 * double(mesh.vertices.size()));
}

TEST_CASE("incremental meshing re-meshes only the changed blocks and equals a fresh mesh") {
	const PinholeIntrinsics camera = rig_camera(1);
	TsdfVolume volume;
	IncrementalMesher mesher;
	for (int i = 0; i < 4; i++) {
		integrate_view(&volume, camera, 90.0 * i, 20.0);
	}
	const std::vector<glm::ivec3> first = volume.take_dirty_blocks();
	CHECK(mesher.update(volume, first) == expected_remesh(volume, first));
	CHECK(meshes_equal(mesher.mesh(), mesh_volume(volume)));

	// One more view from one side changes part of the volume.
	integrate_view(&volume, camera, 30.0, 10.0);
	const std::vector<glm::ivec3> changed = volume.take_dirty_blocks();
	REQUIRE(!changed.empty());
	const int expected = expected_remesh(volume, changed);
	const int meshed = mesher.update(volume, changed);
	MESSAGE("allocated " << volume.stats().allocated_blocks << ", changed " << changed.size() << ", re-meshed " << meshed);
	CHECK(meshed == expected);
	CHECK(meshed < volume.stats().allocated_blocks);
	CHECK(meshes_equal(mesher.mesh(), mesh_volume(volume)));

	SUBCASE("a copy of the changed blocks meshes as the volume was when it was taken") {
		integrate_view(&volume, camera, 200.0, 15.0);
		const TsdfBlockCopy copy(volume, volume.take_dirty_blocks());
		const TriangleMesh then = mesh_volume(volume);
		integrate_view(&volume, camera, 250.0, 25.0); // fused after the copy: not in it
		CHECK(copy.block_count() >= copy.changed_blocks().size());
		CHECK(mesher.update(copy) == expected_remesh(copy, copy.changed_blocks()));
		CHECK(meshes_equal(mesher.mesh(), then));
		// The next copy carries what changed since.
		mesher.update(TsdfBlockCopy(volume, volume.take_dirty_blocks()));
		CHECK(meshes_equal(mesher.mesh(), mesh_volume(volume)));
	}

	SUBCASE("evicted and reset blocks leave the mesh") {
		volume.reset();
		mesher.update(volume, volume.take_dirty_blocks());
		CHECK(mesher.piece_count() == 0);
		CHECK(mesher.mesh().vertices.empty());
	}
}
