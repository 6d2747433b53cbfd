// Pose interpolation (paper §4.3): lerp of the translation, shortest-arc slerp of the rotation.

#include "math/pose.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <initializer_list>
#include <numbers>

using namespace roomprobe;

namespace {

constexpr double TOLERANCE = 1e-9;

double rotation_distance(const glm::dquat &p_a, const glm::dquat &p_b) {
	return std::min(glm::length(p_a - p_b), glm::length(p_a + p_b));
}

// A rigid motion with constant linear velocity and a constant angular rate about a fixed axis:
// exactly what lerp + slerp reproduce between any two of its poses.
struct ConstantMotion {
	glm::dvec3 start_position = glm::dvec3(0.4, 1.5, -2.0);
	glm::dvec3 velocity = glm::dvec3(0.3, -0.05, 0.7); // m/s
	glm::dquat start_rotation = glm::normalize(glm::dquat(0.9, 0.1, -0.3, 0.2));
	glm::dvec3 axis = glm::normalize(glm::dvec3(0.2, 1.0, -0.4));
	double rate = 0.8; // rad/s
	bool world_axis = true; // the axis is fixed in the world (left product) or in the body (right)

	Pose at(double p_t) const {
		Pose pose;
		const glm::dquat turn = glm::angleAxis(rate * p_t, axis);
		pose.rotation = world_axis ? turn * start_rotation : start_rotation * turn;
		pose.translation = start_position + velocity * p_t;
		return pose;
	}
};

void check_same_pose(const Pose &p_actual, const Pose &p_expected, double p_tolerance) {
	CHECK(rotation_distance(p_actual.rotation, p_expected.rotation) < p_tolerance);
	CHECK(glm::length(p_actual.translation - p_expected.translation) < p_tolerance);
	CHECK(std::abs(glm::length(p_actual.rotation) - 1.0) < 1e-12);
}

} // namespace

TEST_CASE("interpolate: between two poses of a constant motion it gives the analytic pose") {
	for (const bool world_axis : { true, false }) {
		ConstantMotion motion;
		motion.world_axis = world_axis;
		// Pairs from consecutive frames (33 ms) to ones 2.5 s (2 rad, < pi) apart.
		for (const double span : { 0.033, 0.5, 2.5 }) {
			const double t0 = 1.25;
			const double t1 = t0 + span;
			const Pose from = motion.at(t0);
			const Pose to = motion.at(t1);
			for (int i = 0; i <= 40; i++) {
				const double alpha = i / 40.0;
				CAPTURE(world_axis);
				CAPTURE(span);
				CAPTURE(alpha);
				check_same_pose(interpolate(from, to, alpha), motion.at(t0 + alpha * span), TOLERANCE);
			}
			// Beyond the pair the same formulas extend the motion at constant velocity.
			check_same_pose(interpolate(from, to, 1.5), motion.at(t0 + 1.5 * span), TOLERANCE);
			check_same_pose(interpolate(from, to, -0.25), motion.at(t0 - 0.25 * span), TOLERANCE);
		}
	}
}

TEST_CASE("interpolate: alpha 0 and 1 give the endpoints exactly") {
	ConstantMotion motion;
	const Pose from = motion.at(0.0);
	const Pose to = motion.at(1.0);
	const Pose at0 = interpolate(from, to, 0.0);
	const Pose at1 = interpolate(from, to, 1.0);
	CHECK(at0.rotation == from.rotation);
	CHECK(at0.translation == from.translation);
	CHECK(at1.rotation == to.rotation);
	CHECK(at1.translation == to.translation);
}

TEST_CASE("interpolate: slerp takes the shortest arc whatever the quaternions' signs") {
	const glm::dvec3 z(0.0, 0.0, 1.0);
	Pose from;
	Pose to;
	to.rotation = glm::angleAxis(170.0 * std::numbers::pi / 180.0, z);
	Pose to_flipped = to;
	to_flipped.rotation = -to.rotation; // the same rotation, the other hemisphere

	for (int i = 0; i <= 10; i++) {
		const double alpha = i / 10.0;
		CAPTURE(alpha);
		const Pose a = interpolate(from, to, alpha);
		const Pose b = interpolate(from, to_flipped, alpha);
		CHECK(rotation_distance(a.rotation, b.rotation) < 1e-12);
		// Shortest arc: 170 * alpha degrees the same way round, never 190 degrees the other way.
		const glm::dquat expected = glm::angleAxis(alpha * 170.0 * std::numbers::pi / 180.0, z);
		CHECK(rotation_distance(a.rotation, expected) < TOLERANCE);
		CHECK(rotation_distance(b.rotation, expected) < TOLERANCE);
	}

	// The same when it is the first pose that is on the far hemisphere.
	Pose from_flipped = from;
	from_flipped.rotation = -from.rotation;
	const glm::dquat half = glm::angleAxis(85.0 * std::numbers::pi / 180.0, z);
	CHECK(rotation_distance(interpolate(from_flipped, to, 0.5).rotation, half) < TOLERANCE);

	// Just past 180 degrees the short way is the other way round: 190 degrees about +z is
	// 170 about -z, so halfway is 85 degrees about -z.
	Pose beyond;
	beyond.rotation = glm::angleAxis(190.0 * std::numbers::pi / 180.0, z);
	CHECK(rotation_distance(interpolate(from, beyond, 0.5).rotation, glm::angleAxis(-85.0 * std::numbers::pi / 180.0, z)) < TOLERANCE);
}

TEST_CASE("interpolate: nearly equal rotations interpolate without losing digits") {
	const glm::dvec3 axis = glm::normalize(glm::dvec3(1.0, 2.0, 3.0));
	for (const double angle : { 0.0, 1e-15, 1e-12, 1e-9, 1e-6 }) {
		CAPTURE(angle);
		Pose from;
		from.rotation = glm::normalize(glm::dquat(0.3, -0.5, 0.1, 0.8));
		Pose to;
		to.rotation = glm::angleAxis(angle, axis) * from.rotation;
		const Pose mid = interpolate(from, to, 0.3);
		CHECK(std::isfinite(mid.rotation.w));
		CHECK(rotation_distance(mid.rotation, glm::angleAxis(0.3 * angle, axis) * from.rotation) < 1e-15 + 1e-12);
	}
}
