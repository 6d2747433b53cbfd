// Rigid-pose algebra (math/pose.h): compose, inverse, transform_point and their matrices.

#include "math/pose.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include <cmath>
#include <numbers>
#include <random>

using namespace roomprobe;

namespace {

constexpr double TOLERANCE = 1e-12;

Pose random_pose(std::mt19937_64 &r_rng) {
	std::normal_distribution<double> gaussian(0.0, 1.0);
	std::uniform_real_distribution<double> uniform(-5.0, 5.0);
	Pose pose;
	// Normalised Gaussian 4-vectors are uniform on the sphere of rotations.
	pose.rotation = glm::normalize(glm::dquat(gaussian(r_rng), gaussian(r_rng), gaussian(r_rng), gaussian(r_rng)));
	pose.translation = glm::dvec3(uniform(r_rng), uniform(r_rng), uniform(r_rng));
	return pose;
}

glm::dvec3 random_point(std::mt19937_64 &r_rng) {
	std::uniform_real_distribution<double> uniform(-3.0, 3.0);
	return glm::dvec3(uniform(r_rng), uniform(r_rng), uniform(r_rng));
}

double distance(const glm::dvec3 &p_a, const glm::dvec3 &p_b) {
	return glm::length(p_a - p_b);
}

// q and -q are the same rotation.
double rotation_distance(const glm::dquat &p_a, const glm::dquat &p_b) {
	return std::min(glm::length(p_a - p_b), glm::length(p_a + p_b));
}

double max_abs_difference(const glm::dmat4 &p_a, const glm::dmat4 &p_b) {
	double worst = 0.0;
	for (int c = 0; c < 4; c++) {
		for (int r = 0; r < 4; r++) {
			worst = std::max(worst, std::abs(p_a[c][r] - p_b[c][r]));
		}
	}
	return worst;
}

} // namespace

TEST_CASE("pose: a known rotation and translation move a point where expected") {
	Pose pose;
	pose.rotation = glm::angleAxis(std::numbers::pi / 2.0, glm::dvec3(0.0, 0.0, 1.0)); // +90 degrees about z
	pose.translation = glm::dvec3(1.0, 2.0, 3.0);
	CHECK(distance(transform_point(pose, glm::dvec3(1.0, 0.0, 0.0)), glm::dvec3(1.0, 3.0, 3.0)) < TOLERANCE);
	CHECK(distance(transform_point(pose, glm::dvec3(0.0, 1.0, 0.0)), glm::dvec3(0.0, 2.0, 3.0)) < TOLERANCE);
	CHECK(distance(transform_point(inverse(pose), glm::dvec3(1.0, 3.0, 3.0)), glm::dvec3(1.0, 0.0, 0.0)) < TOLERANCE);
	// The default pose is the identity.
	const Pose identity;
	CHECK(transform_point(identity, glm::dvec3(4.0, -5.0, 6.0)) == glm::dvec3(4.0, -5.0, 6.0));
}

TEST_CASE("pose: compose and inverse identities hold on random poses") {
	std::mt19937_64 rng(20240611);
	for (int i = 0; i < 500; i++) {
		const Pose a = random_pose(rng);
		const Pose b = random_pose(rng);
		const Pose c = random_pose(rng);
		const glm::dvec3 x = random_point(rng);
		CAPTURE(i);

		const Pose a_inv_a = compose(inverse(a), a);
		const Pose a_a_inv = compose(a, inverse(a));
		CHECK(rotation_distance(a_inv_a.rotation, glm::dquat(1.0, 0.0, 0.0, 0.0)) < TOLERANCE);
		CHECK(glm::length(a_inv_a.translation) < TOLERANCE);
		CHECK(rotation_distance(a_a_inv.rotation, glm::dquat(1.0, 0.0, 0.0, 0.0)) < TOLERANCE);
		CHECK(glm::length(a_a_inv.translation) < TOLERANCE);

		const Pose a_inv_inv = inverse(inverse(a));
		CHECK(rotation_distance(a_inv_inv.rotation, a.rotation) < TOLERANCE);
		CHECK(distance(a_inv_inv.translation, a.translation) < TOLERANCE);

		// Associativity, and (a b)^-1 = b^-1 a^-1.
		const Pose left = compose(compose(a, b), c);
		const Pose right = compose(a, compose(b, c));
		CHECK(rotation_distance(left.rotation, right.rotation) < TOLERANCE);
		CHECK(distance(left.translation, right.translation) < TOLERANCE);
		const Pose ab_inv = inverse(compose(a, b));
		const Pose b_inv_a_inv = compose(inverse(b), inverse(a));
		CHECK(rotation_distance(ab_inv.rotation, b_inv_a_inv.rotation) < TOLERANCE);
		CHECK(distance(ab_inv.translation, b_inv_a_inv.translation) < TOLERANCE);

		// Composition is applying one after the other; the inverse undoes.
		CHECK(distance(transform_point(compose(a, b), x), transform_point(a, transform_point(b, x))) < TOLERANCE);
		CHECK(distance(transform_point(inverse(a), transform_point(a, x)), x) < TOLERANCE);
		CHECK(std::abs(glm::length(compose(a, b).rotation) - 1.0) < TOLERANCE);
	}
}

TEST_CASE("pose: transform_point, compose and inverse agree with 4x4 matrices") {
	std::mt19937_64 rng(7);
	for (int i = 0; i < 500; i++) {
		const Pose a = random_pose(rng);
		const Pose b = random_pose(rng);
		const glm::dvec3 x = random_point(rng);
		CAPTURE(i);
		const glm::dmat4 m_a = pose_to_matrix(a);
		const glm::dmat4 m_b = pose_to_matrix(b);

		// The bottom row is (0, 0, 0, 1) and the 3x3 is orthonormal.
		CHECK(m_a[0][3] == 0.0);
		CHECK(m_a[1][3] == 0.0);
		CHECK(m_a[2][3] == 0.0);
		CHECK(m_a[3][3] == 1.0);
		const glm::dmat3 r(m_a);
		CHECK(max_abs_difference(glm::dmat4(glm::transpose(r) * r), glm::dmat4(1.0)) < TOLERANCE);
		CHECK(std::abs(glm::determinant(r) - 1.0) < TOLERANCE);

		CHECK(distance(glm::dvec3(m_a * glm::dvec4(x, 1.0)), transform_point(a, x)) < TOLERANCE);
		CHECK(max_abs_difference(pose_to_matrix(compose(a, b)), m_a * m_b) < TOLERANCE);
		CHECK(max_abs_difference(pose_to_matrix(inverse(a)), glm::inverse(m_a)) < TOLERANCE);

		const Pose back = pose_from_matrix(m_a);
		CHECK(rotation_distance(back.rotation, a.rotation) < TOLERANCE);
		CHECK(distance(back.translation, a.translation) < TOLERANCE);
	}
}

TEST_CASE("pose: is_finite and normalize_rotation") {
	Pose pose;
	CHECK(is_finite(pose));
	pose.translation.y = std::nan("");
	CHECK_FALSE(is_finite(pose));
	pose = Pose();
	pose.rotation.w = INFINITY;
	CHECK_FALSE(is_finite(pose));

	glm::dquat q(1.0 + 5e-7, 0.0, 0.0, 0.0);
	CHECK(normalize_rotation(&q, 1e-6));
	CHECK(std::abs(glm::length(q) - 1.0) < 1e-15);
	glm::dquat far(0.5, 0.0, 0.5, 0.0);
	CHECK_FALSE(normalize_rotation(&far, 1e-6));
	CHECK(far == glm::dquat(0.5, 0.0, 0.5, 0.0)); // left unchanged
	glm::dquat zero(0.0, 0.0, 0.0, 0.0);
	CHECK_FALSE(normalize_rotation(&zero, 1e-6));
	glm::dquat not_finite(std::nan(""), 0.0, 0.0, 0.0);
	CHECK_FALSE(normalize_rotation(&not_finite, 1.0));
}
