// Distance-aware reflections (envmap/parallax.h): the map's distances lead a ray from off the
// map's centre to the surface it meets, checked against the exact hit in a box room and a
// spherical one; the coarse render's and the truth's distances (eval/truth_scene.h).

#include <io/opencv.h>

#include "envmap/coarse_render.h"
#include "envmap/parallax.h"
#include "eval/truth_scene.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace roomprobe;

namespace {

constexpr double DEG = std::numbers::pi / 180.0;

Floorplan box_floorplan() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 3.0 }, { 0.0, 3.0 } };
	floorplan.ceiling_height_m = 2.5;
	return floorplan;
}

double angle(const glm::dvec3 &p_a, const glm::dvec3 &p_b) {
	return std::acos(std::clamp(glm::dot(glm::normalize(p_a), glm::normalize(p_b)), -1.0, 1.0));
}

} // namespace

TEST_CASE("parallax: a map without distances is read along the ray itself") {
	const Cubemap map = make_cubemap(8, cv::Vec3f(1.0f, 1.0f, 1.0f));
	CHECK_FALSE(has_distances(map));
	const glm::dvec3 r = glm::normalize(glm::dvec3(0.3, -0.2, 0.9));
	CHECK(glm::length(parallax_direction(map, glm::dvec3(0.0), glm::dvec3(0.4, 0.1, 0.0), r) - r) < 1e-12);
	CHECK(sample_distance(map, r) == 0.0);
}

TEST_CASE("parallax: in a spherical room the surface is found exactly") {
	// Every texel 2.5 m away: the surface is the sphere of radius 2.5 about the centre.
	Cubemap map = make_cubemap(16);
	for (cv::Mat &face : map.distance_m) {
		face = cv::Mat(16, 16, CV_32FC1, cv::Scalar(2.5f));
	}
	REQUIRE(has_distances(map));
	const glm::dvec3 centre(1.0, 1.2, 0.5);
	std::mt19937 random(5);
	std::uniform_real_distribution<double> unit(-1.0, 1.0);
	for (int i = 0; i < 200; i++) {
		const glm::dvec3 point = centre + 0.8 * glm::dvec3(unit(random), unit(random), unit(random)) / std::sqrt(3.0);
		const glm::dvec3 r = glm::normalize(glm::dvec3(unit(random), unit(random), unit(random)) + glm::dvec3(1e-3));
		// The exact hit: the far root of |point - centre + t r| = 2.5.
		const glm::dvec3 o = point - centre;
		const double b = glm::dot(o, r), t = -b + std::sqrt(b * b - glm::dot(o, o) + 2.5 * 2.5);
		CHECK(angle(parallax_direction(map, centre, point, r), o + t * r) < 1e-6);
	}
}

TEST_CASE("parallax: in a box room, the coarse render's distances lead rays from a mirror's surface to the wall they meet") {
	const Floorplan floorplan = box_floorplan();
	const RoomMeshResult mesh = build_room_mesh(floorplan);
	REQUIRE_MESSAGE(mesh.ok, mesh.error);
	const CoarseCubemapRenderer renderer(mesh.mesh);
	const glm::dvec3 centre(2.0, 1.25, 1.5), room_max(4.0, 2.5, 3.0);
	// The exact distance to the prism (intersect_room: checked against the box's planes in
	// test_envmap_coarse_render.cpp).
	auto distance = [&](const glm::dvec3 &p_origin, const glm::dvec3 &p_direction) {
		RoomRayHit hit;
		REQUIRE(intersect_room(mesh.mesh, p_origin, p_direction, &hit));
		return hit.distance;
	};
	const int size = 128;
	const Cubemap map = renderer.render(cv::Mat(mesh.mesh.atlas_height, mesh.mesh.atlas_width, CV_32FC3, cv::Scalar::all(0.5)), centre, size);
	REQUIRE(has_distances(map));
	// The render's distances are the prism's, texel by texel.
	for (int f = 0; f < 6; f++) {
		for (int v = 0; v < size; v += 9) {
			for (int u = 0; u < size; u += 7) {
				const glm::dvec3 d = cubemap_direction(f, u, v, size);
				CHECK(map.distance_m[size_t(f)].at<float>(v, u) == doctest::Approx(distance(centre, d)).epsilon(1e-6));
			}
		}
	}
	// Points on a 0.6 m sphere about a centre 1.1 m from the probe, 0.3 m from a wall: the plain
	// lookup's direction is off by up to tens of degrees; the distance-aware one leads to the hit.
	std::mt19937 random(11);
	std::normal_distribution<double> gauss;
	const glm::dvec3 sphere(3.1, 1.25, 1.5);
	int samples = 0, within_a_degree = 0;
	double plain_sum = 0.0, aware_sum = 0.0;
	for (int i = 0; i < 2000; i++) {
		const glm::dvec3 normal = glm::normalize(glm::dvec3(gauss(random), gauss(random), gauss(random)));
		glm::dvec3 r = glm::normalize(glm::dvec3(gauss(random), gauss(random), gauss(random)));
		if (glm::dot(r, normal) < 0.0) {
			r = -r; // leaving the sphere
		}
		const glm::dvec3 point = sphere + 0.6 * normal;
		const glm::dvec3 hit = point + distance(point, r) * r;
		// Away from the box's edges, where the map's texels blend two walls.
		int near_planes = 0;
		for (int axis = 0; axis < 3; axis++) {
			near_planes += (hit[axis] < 0.1 || hit[axis] > room_max[axis] - 0.1) ? 1 : 0;
		}
		if (near_planes > 1) {
			continue;
		}
		samples++;
		const double plain = angle(r, hit - centre), aware = angle(parallax_direction(map, centre, point, r), hit - centre);
		plain_sum += plain;
		aware_sum += aware;
		within_a_degree += aware < 1.0 * DEG ? 1 : 0;
	}
	REQUIRE(samples > 1000);
	// What is left is the map's own sampling: a 128-px face's texel spans 0.7 deg, and the
	// distances are read bilinearly within a face (clamped at its seams). Measured: 0.04 deg mean,
	// 99.6 % within a degree (the rest near a face seam).
	MESSAGE("mean direction error: plain " << plain_sum / samples / DEG << " deg, distance-aware " << aware_sum / samples / DEG << " deg, "
										   << 100.0 * within_a_degree / samples << " % within a degree");
	CHECK(plain_sum / samples > 10.0 * DEG); // parallax matters here
	CHECK(aware_sum / samples < 0.25 * DEG);
	CHECK(within_a_degree >= 0.98 * samples);
}

TEST_CASE("truth scene: what lies on the room's prism, and the true distances from a probe") {
	const Floorplan floorplan = box_floorplan();
	CHECK(on_prism(floorplan, glm::dvec3(1.0, 0.0, 1.0))); // floor
	CHECK(on_prism(floorplan, glm::dvec3(1.0, 2.48, 1.0))); // a panel 2 cm under the ceiling
	CHECK(on_prism(floorplan, glm::dvec3(3.99, 1.0, 1.0))); // a wall
	CHECK_FALSE(on_prism(floorplan, glm::dvec3(3.9, 1.0, 1.0))); // 10 cm in front of it
	CHECK_FALSE(on_prism(floorplan, glm::dvec3(2.0, 0.75, 1.5))); // a table top

	synth::SceneOptions options;
	const synth::SceneResult scene = synth::make_scene("two_rooms", options);
	REQUIRE_MESSAGE(scene.ok, scene.error);
	const synth::SynthRenderer renderer(scene.scene);
	REQUIRE(renderer.ok());
	const Floorplan &room = scene.scene.room.floorplan;
	const glm::dvec3 probe = scene.scene.probe_position;
	const int size = 16;
	const auto prism = prism_directions(renderer, room, probe, size);
	const auto distances = true_distances(renderer, probe, size);
	// Straight up from the probe is the ceiling (or a lamp on it); straight down the table the probe
	// sits over, 15 cm below.
	int face = 0;
	double u = 0.0, v = 0.0;
	cubemap_face_pixel(glm::dvec3(0.0, 1.0, 0.0), size, &face, &u, &v);
	CHECK(prism[size_t(face)].at<uint8_t>(int(v), int(u)) == 255);
	CHECK(distances[size_t(face)].at<float>(int(v), int(u)) == doctest::Approx(room.ceiling_height_m - probe.y).epsilon(0.02));
	cubemap_face_pixel(glm::dvec3(0.0, -1.0, 0.0), size, &face, &u, &v);
	CHECK(prism[size_t(face)].at<uint8_t>(int(v), int(u)) == 0);
	CHECK(distances[size_t(face)].at<float>(int(v), int(u)) < 0.5f);
}
