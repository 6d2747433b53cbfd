// Virtual objects drawn into a probe's map (prt/virtual_objects.h, paper §4.7's last
// paragraph): known scenes whose answer is worked out by hand.

#include "prt_test_meshes.h"

#include "prt/virtual_objects.h"
#include "prt/contact_shadow.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

using namespace roomprobe;

namespace {

// Uniform radiance p_value from every direction, in SH: only y_0^0, sqrt(4 pi) x the value.
ShCoefficients uniform_light(double p_value) {
	ShCoefficients sh{};
	sh[0] = glm::dvec3(p_value * std::sqrt(4.0 * std::numbers::pi));
	return sh;
}

glm::dvec3 texel(const Cubemap &p_map, const glm::dvec3 &p_direction) {
	int face = 0;
	double u = 0.0, v = 0.0;
	cubemap_face_pixel(p_direction, p_map.size, &face, &u, &v);
	const cv::Vec3f c = p_map.faces[size_t(face)].at<cv::Vec3f>(int(std::lround(v)), int(std::lround(u)));
	return glm::dvec3(c[0], c[1], c[2]);
}

} // namespace

TEST_CASE("virtual objects: a diffuse sphere in uniform light covers its solid angle in its albedo") {
	VirtualObject ball;
	ball.mesh = uv_sphere(glm::vec3(0.0f, 0.0f, 1.0f), 0.2f, 48, 96); // 1 m along +Z from the probe
	ball.color = glm::dvec3(0.9, 0.1, 0.1);
	std::shared_ptr<const VirtualScene> scene;
	REQUIRE(VirtualScene::make({ ball }, &scene) == "");
	Cubemap map = make_cubemap(128, cv::Vec3f(0.5f, 0.5f, 0.5f));
	const VirtualDrawStats stats = scene->draw(glm::dvec3(0.0), uniform_light(1.0), nullptr, &map);
	// Uniform radiance 1: irradiance pi everywhere, so a Lambertian surface shows its albedo.
	const glm::dvec3 centre = texel(map, glm::dvec3(0.0, 0.0, 1.0));
	CHECK(glm::length(centre - ball.color) < 2e-3);
	CHECK(glm::length(texel(map, glm::dvec3(0.0, 0.0, -1.0)) - glm::dvec3(0.5)) < 1e-6); // behind: the room
	// The texels drawn cover the sphere's solid angle 2 pi (1 - cos asin(0.2)).
	double drawn = 0.0;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < map.size; y++) {
			for (int x = 0; x < map.size; x++) {
				if (map.faces[size_t(f)].at<cv::Vec3f>(y, x)[2] < 0.3f) {
					drawn += cubemap_texel_solid_angle(x, y, map.size);
				}
			}
		}
	}
	const double expected = 2.0 * std::numbers::pi * (1.0 - std::sqrt(1.0 - 0.04));
	CHECK(drawn == doctest::Approx(expected).epsilon(0.03));
	CHECK(stats.texels_drawn > 0);
	// Only the cone of the bounding sphere is traced: a small share of the map.
	CHECK(stats.texels_traced < size_t(6 * 128 * 128) / 20);
}

TEST_CASE("virtual objects: a mirror shows the previous map along the reflection, glass mostly what is behind it") {
	// The previous map: each face its own colour.
	Cubemap previous = make_cubemap(32);
	const cv::Vec3f colours[6] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 1, 0 }, { 0, 1, 1 }, { 1, 0, 1 } };
	for (int f = 0; f < 6; f++) {
		previous.faces[size_t(f)].setTo(colours[f]);
	}
	VirtualObject mirror;
	mirror.look = VirtualLook::Mirror;
	mirror.mesh = uv_sphere(glm::vec3(0.0f, 0.0f, 1.0f), 0.2f, 48, 96);
	mirror.color = glm::dvec3(0.5);
	std::shared_ptr<const VirtualScene> scene;
	REQUIRE(VirtualScene::make({ mirror }, &scene) == "");
	Cubemap map = make_cubemap(64, cv::Vec3f(0.2f, 0.2f, 0.2f));
	scene->draw(glm::dvec3(0.0), uniform_light(1.0), &previous, &map);
	// Its nearest point faces the probe: the reflection goes back along -Z (face 5, magenta).
	CHECK(glm::length(texel(map, glm::dvec3(0.0, 0.0, 1.0)) - glm::dvec3(0.5, 0.0, 0.5)) < 1e-3);
	// Glass of index 1.5 head-on reflects 4 %: the rest is what lies behind it, +Z (face 4, cyan).
	VirtualObject glass = mirror;
	glass.look = VirtualLook::Glass;
	glass.color = glm::dvec3(1.0);
	REQUIRE(VirtualScene::make({ glass }, &scene) == "");
	map = make_cubemap(64, cv::Vec3f(0.2f, 0.2f, 0.2f));
	scene->draw(glm::dvec3(0.0), uniform_light(1.0), &previous, &map);
	CHECK(glm::length(texel(map, glm::dvec3(0.0, 0.0, 1.0)) - glm::dvec3(0.04, 0.96, 1.0)) < 5e-3);
}

TEST_CASE("virtual objects: a shadow catcher darkens the table under its object in the map, as prt/contact_shadow.h says") {
	// A sphere of radius 0.25 resting on the plane y = 0; the probe 1 m above, looking down.
	const PrtMesh sphere = uv_sphere(glm::vec3(0.0f, 0.25f, 0.0f), 0.25f, 24, 48);
	TransferOptions options;
	options.samples_per_vertex = 1024;
	const ShadowCatcher baked = bake_shadow_catcher(sphere, glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), 1.0, 40, options);
	REQUIRE(baked.error == "");
	VirtualObject catcher;
	catcher.look = VirtualLook::ShadowCatcher;
	catcher.mesh = baked.plane;
	catcher.transfer = baked.transfer;
	std::shared_ptr<const VirtualScene> scene;
	REQUIRE(VirtualScene::make({ catcher }, &scene) == "");
	Cubemap map = make_cubemap(128, cv::Vec3f(0.6f, 0.6f, 0.6f));
	const glm::dvec3 probe(0.6, 1.0, 0.0);
	scene->draw(probe, uniform_light(1.0), nullptr, &map);
	// At a plane point a distance d from the contact, the sphere's form factor is (R / D)^3 with
	// D = sqrt(d^2 + R^2) (tests/core/test_prt_transfer.cpp): under a uniform sky the table keeps
	// 1 - (R / D)^3 of its light. Here at d = 0.3 and 0.9 m.
	for (double d : { 0.3, 0.9 }) {
		const double r = 0.25, analytic = 1.0 - std::pow(r / std::sqrt(d * d + r * r), 3.0);
		const glm::dvec3 seen = texel(map, glm::normalize(glm::dvec3(d, 0.0, 0.0) - probe));
		CAPTURE(d);
		// The bake's 1024 samples (about 2 %), the 5-cm grid's interpolation and the texel's
		// footprint on the plane (about 1.5 cm) against the ratio's slope.
		CHECK(std::abs(seen.x / 0.6 - analytic) < 0.05);
	}
	// Outside the catcher the room is untouched.
	CHECK(glm::length(texel(map, glm::dvec3(0.0, 1.0, 0.0)) - glm::dvec3(0.6)) < 1e-6);
}

TEST_CASE("virtual objects: bad objects are refused with the reason") {
	std::shared_ptr<const VirtualScene> scene;
	VirtualObject broken;
	broken.mesh = uv_sphere(glm::vec3(0.0f), 0.2f, 4, 8);
	broken.mesh.indices.push_back(100000);
	broken.mesh.indices.push_back(0);
	broken.mesh.indices.push_back(1);
	CHECK(VirtualScene::make({ broken }, &scene).find("virtual object 0") == 0);
	VirtualObject catcher;
	catcher.look = VirtualLook::ShadowCatcher;
	catcher.mesh = uv_sphere(glm::vec3(0.0f), 0.2f, 4, 8);
	CHECK(VirtualScene::make({ catcher }, &scene).find("one transfer vector per vertex") != std::string::npos);
	CHECK(scene == nullptr);
}
