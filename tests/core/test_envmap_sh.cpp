// Projecting cubemaps onto 5 bands of real spherical harmonics (paper §4.8), and back.

#include <io/opencv.h>

#include "envmap/spherical_harmonics.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

using namespace roomprobe;

namespace {

Cubemap cubemap_of(int p_size, const std::function<glm::dvec3(const glm::dvec3 &)> &p_function) {
	Cubemap cubemap = make_cubemap(p_size);
	for (int face = 0; face < 6; face++) {
		for (int v = 0; v < p_size; v++) {
			for (int u = 0; u < p_size; u++) {
				const glm::dvec3 value = p_function(cubemap_direction(face, u, v, p_size));
				cubemap.faces[size_t(face)].at<cv::Vec3f>(v, u) = cv::Vec3f(float(value.x), float(value.y), float(value.z));
			}
		}
	}
	return cubemap;
}

glm::dvec3 random_direction(std::mt19937 &p_rng) {
	std::normal_distribution<double> normal;
	glm::dvec3 d(0.0);
	while (glm::length(d) < 1e-6) {
		d = glm::dvec3(normal(p_rng), normal(p_rng), normal(p_rng));
	}
	return glm::normalize(d);
}

} // namespace

TEST_CASE("texel solid angles cover the sphere") {
	for (int n : { 1, 2, 7, 64 }) {
		double total = 0.0;
		for (int v = 0; v < n; v++) {
			for (int u = 0; u < n; u++) {
				total += cubemap_texel_solid_angle(u, v, n);
			}
		}
		CHECK(6.0 * total == doctest::Approx(4.0 * std::numbers::pi).epsilon(1e-12));
	}
	// A corner texel is smaller than a centre one.
	CHECK(cubemap_texel_solid_angle(0, 0, 8) < cubemap_texel_solid_angle(3, 4, 8));
}

TEST_CASE("the SH basis follows Sloan's real, orthonormal convention and ordering") {
	const double pi = std::numbers::pi;
	const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
	const auto y = sh_basis(d);
	CHECK(y[0] == doctest::Approx(0.5 / std::sqrt(pi)));
	CHECK(y[sh_index(1, -1)] == doctest::Approx(-std::sqrt(3.0 / (4.0 * pi)) * d.y));
	CHECK(y[sh_index(1, 0)] == doctest::Approx(std::sqrt(3.0 / (4.0 * pi)) * d.z));
	CHECK(y[sh_index(1, 1)] == doctest::Approx(-std::sqrt(3.0 / (4.0 * pi)) * d.x));
	CHECK(y[sh_index(2, -2)] == doctest::Approx(std::sqrt(15.0 / (4.0 * pi)) * d.x * d.y));
	CHECK(y[sh_index(2, -1)] == doctest::Approx(-std::sqrt(15.0 / (4.0 * pi)) * d.y * d.z));
	CHECK(y[sh_index(2, 0)] == doctest::Approx(std::sqrt(5.0 / (16.0 * pi)) * (3.0 * d.z * d.z - 1.0)));
	CHECK(y[sh_index(2, 1)] == doctest::Approx(-std::sqrt(15.0 / (4.0 * pi)) * d.x * d.z));
	CHECK(y[sh_index(2, 2)] == doctest::Approx(std::sqrt(15.0 / (16.0 * pi)) * (d.x * d.x - d.y * d.y)));
	// Band 3 and 4 samples (Sloan's table).
	CHECK(y[sh_index(3, 0)] == doctest::Approx(std::sqrt(7.0 / (16.0 * pi)) * d.z * (5.0 * d.z * d.z - 3.0)));
	CHECK(y[sh_index(3, -3)] == doctest::Approx(-std::sqrt(35.0 / (32.0 * pi)) * d.y * (3.0 * d.x * d.x - d.y * d.y)));
	CHECK(y[sh_index(4, 0)] == doctest::Approx(3.0 / (16.0 * std::sqrt(pi)) * (35.0 * std::pow(d.z, 4) - 30.0 * d.z * d.z + 3.0)));
	CHECK(y[sh_index(4, 4)] == doctest::Approx(3.0 / 16.0 * std::sqrt(35.0 / pi) * (std::pow(d.x, 4) - 6.0 * d.x * d.x * d.y * d.y + std::pow(d.y, 4))));
	CHECK(y[sh_index(4, -4)] == doctest::Approx(3.0 / 4.0 * std::sqrt(35.0 / pi) * d.x * d.y * (d.x * d.x - d.y * d.y)));
	// Unnormalised input is normalised.
	const auto y2 = sh_basis(d * 3.0);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		CHECK(y2[size_t(i)] == doctest::Approx(y[size_t(i)]));
	}
}

TEST_CASE("projecting a constant cubemap gives only c00 = sqrt(4 pi) value") {
	const glm::dvec3 value(0.7, 0.25, 1.5);
	const ShCoefficients c = project_sh(cubemap_of(64, [&](const glm::dvec3 &) { return value; }));
	for (int k = 0; k < 3; k++) {
		CHECK(c[0][k] == doctest::Approx(std::sqrt(4.0 * std::numbers::pi) * value[k]).epsilon(1e-6));
	}
	for (int i = 1; i < SH_COEFFICIENTS; i++) {
		for (int k = 0; k < 3; k++) {
			CHECK(std::abs(c[size_t(i)][k]) < 1e-3); // quadrature error; cubic symmetry leaves only band 4
		}
	}
	// Evaluating gives the constant back everywhere.
	std::mt19937 rng(3);
	for (int i = 0; i < 20; i++) {
		const glm::dvec3 back = evaluate_sh(c, random_direction(rng));
		CHECK(glm::length(back - value) < 1e-3); // texel-centre quadrature error, O(1 / size^2)
	}
}

TEST_CASE("projecting a single basis function gives 1 at its own index and 0 elsewhere") {
	const int n = 64;
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		const Cubemap cubemap = cubemap_of(n, [&](const glm::dvec3 &p_d) {
			const double y = sh_basis(p_d)[size_t(i)];
			return glm::dvec3(y, 2.0 * y, -y);
		});
		const ShCoefficients c = project_sh(cubemap);
		for (int j = 0; j < SH_COEFFICIENTS; j++) {
			const double expected = i == j ? 1.0 : 0.0;
			CHECK_MESSAGE(std::abs(c[size_t(j)].x - expected) < 1e-3, "basis ", i, " coefficient ", j, ": ", c[size_t(j)].x);
			CHECK(std::abs(c[size_t(j)].y - 2.0 * expected) < 2e-3);
			CHECK(std::abs(c[size_t(j)].z + expected) < 1e-3);
		}
	}
}

TEST_CASE("a band-limited function survives projection and evaluation") {
	// A polynomial of degree 4 in the direction's components lies in bands 0..4.
	const auto f = [](const glm::dvec3 &p_d) {
		const double r = 0.5 + 0.3 * p_d.x + 0.2 * p_d.y * p_d.z + 0.4 * std::pow(p_d.y, 4);
		const double g = 1.0 - 0.5 * p_d.z * p_d.z + 0.1 * p_d.x * p_d.y * p_d.z;
		const double b = 0.2 + 0.6 * p_d.x * p_d.x * p_d.y * p_d.z;
		return glm::dvec3(r, g, b);
	};
	const ShCoefficients c = project_sh(cubemap_of(64, f));
	std::mt19937 rng(7);
	for (int i = 0; i < 200; i++) {
		const glm::dvec3 d = random_direction(rng);
		const glm::dvec3 back = evaluate_sh(c, d);
		const glm::dvec3 expected = f(d);
		CHECK(std::abs(back.x - expected.x) < 1e-3);
		CHECK(std::abs(back.y - expected.y) < 1e-3);
		CHECK(std::abs(back.z - expected.z) < 1e-3);
	}
}

TEST_CASE("the cosine-lobe convolution turns radiance into irradiance") {
	const double pi = std::numbers::pi;
	// Radiance 1 + z: irradiance at normal n is pi + (2 pi / 3) n.z.
	const ShCoefficients radiance = project_sh(cubemap_of(64, [](const glm::dvec3 &p_d) { return glm::dvec3(1.0 + p_d.z, 1.0, 0.0); }));
	const ShCoefficients irradiance = convolve_cosine_lobe(radiance);
	std::mt19937 rng(11);
	for (int i = 0; i < 50; i++) {
		const glm::dvec3 normal = random_direction(rng);
		const glm::dvec3 e = evaluate_sh(irradiance, normal);
		CHECK(e.x == doctest::Approx(pi + 2.0 * pi / 3.0 * normal.z).epsilon(1e-3));
		CHECK(e.y == doctest::Approx(pi).epsilon(1e-3));
		CHECK(std::abs(e.z) < 1e-4);
	}
	CHECK(sh_cosine_lobe_factor(3) == 0.0);
	CHECK(sh_cosine_lobe_factor(4) == doctest::Approx(-pi / 24.0));
	// An invalid cubemap projects to zeros.
	const ShCoefficients none = project_sh(Cubemap());
	CHECK(glm::length(none[0]) == 0.0);
}

TEST_CASE("the projection of large faces box-filtered to 64^2 matches the full projection") {
	// A room-like map with hard edges: a bright window, a dim floor, a smooth sky gradient. The
	// filtered faces give the same irradiance as the full 256^2 faces within 0.2 % of its mean
	// (the texel-centre quadrature error of 64^2, about 1e-3 relative in the tests above).
	const auto f = [](const glm::dvec3 &p_d) {
		if (p_d.x > 0.7 && std::abs(p_d.y) < 0.3) {
			return glm::dvec3(20.0, 18.0, 15.0);
		}
		return p_d.y < -0.2 ? glm::dvec3(0.1, 0.08, 0.05) : glm::dvec3(0.5 + 0.3 * p_d.y, 0.6, 0.8 - 0.2 * p_d.z);
	};
	const Cubemap map = cubemap_of(256, f);
	const ShCoefficients full = convolve_cosine_lobe(project_sh(map, 0));
	const ShCoefficients filtered = convolve_cosine_lobe(project_sh(map));
	const ShCoefficients at_64 = convolve_cosine_lobe(project_sh(map, 64));
	const double mean = evaluate_sh(full, glm::dvec3(0.0, 1.0, 0.0)).x;
	std::mt19937 rng(5);
	for (int i = 0; i < 100; i++) {
		const glm::dvec3 n = random_direction(rng);
		const glm::dvec3 e_full = evaluate_sh(full, n);
		const glm::dvec3 e_filtered = evaluate_sh(filtered, n);
		CHECK(glm::length(e_filtered - e_full) < 2e-3 * mean);
		CHECK(glm::length(evaluate_sh(at_64, n) - e_filtered) == 0.0);
	}
	// Maps at or under the size are projected as they are.
	const Cubemap small = cubemap_of(32, f);
	const ShCoefficients a = project_sh(small), b = project_sh(small, 0);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		CHECK(glm::length(a[size_t(i)] - b[size_t(i)]) == 0.0);
	}
}

TEST_CASE("spherical harmonics: rotate_sh gives the function seen from a rotated frame, band by band") {
	// A 5-band function with every coefficient set, and a rotation about a skew axis.
	ShCoefficients c{};
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		c[size_t(i)] = glm::dvec3(std::sin(1.7 * i + 0.3), std::cos(0.9 * i), 0.5 - 0.04 * i);
	}
	const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, -0.8, 0.5));
	const double angle = 1.1;
	// Rodrigues' rotation matrix.
	const glm::dmat3 k(0.0, axis.z, -axis.y, -axis.z, 0.0, axis.x, axis.y, -axis.x, 0.0);
	const glm::dmat3 rotation = glm::dmat3(1.0) + std::sin(angle) * k + (1.0 - std::cos(angle)) * k * k;
	const ShCoefficients rotated = rotate_sh(c, rotation);
	double worst = 0.0;
	for (int i = 0; i < 200; i++) {
		const double z = 1.0 - (2.0 * i + 1.0) / 200.0, r = std::sqrt(1.0 - z * z), phi = 0.7 * i;
		const glm::dvec3 d(r * std::cos(phi), r * std::sin(phi), z);
		worst = std::max(worst, glm::length(evaluate_sh(rotated, d) - evaluate_sh(c, rotation * d)));
	}
	CHECK(worst < 1e-9);
	// Energy stays in its band, and the identity changes nothing.
	const ShCoefficients same = rotate_sh(c, glm::dmat3(1.0));
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		CHECK(glm::length(same[size_t(i)] - c[size_t(i)]) < 1e-12);
	}
	double band2_before = 0.0, band2_after = 0.0;
	for (int m = -2; m <= 2; m++) {
		band2_before += glm::dot(c[size_t(sh_index(2, m))], c[size_t(sh_index(2, m))]);
		band2_after += glm::dot(rotated[size_t(sh_index(2, m))], rotated[size_t(sh_index(2, m))]);
	}
	CHECK(band2_after == doctest::Approx(band2_before).epsilon(1e-9));
}
