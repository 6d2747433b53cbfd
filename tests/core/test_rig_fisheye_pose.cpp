// The fisheye's pose at its own timestamps (paper §4.3): interpolate the RGB-D trajectory at the
// fisheye's instant on the RGB-D clock, then apply the fixed extrinsic.

#include "rig/fisheye_pose.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

using namespace roomprobe;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

double rotation_distance(const glm::dquat &p_a, const glm::dquat &p_b) {
	return std::min(glm::length(p_a - p_b), glm::length(p_a + p_b));
}

// The RGB-D camera's world_from_rgb on its own clock: constant linear and angular velocity.
Pose rgb_motion_at(double p_t) {
	Pose pose;
	const glm::dquat start = glm::normalize(glm::dquat(0.2, 0.9, -0.1, 0.3));
	pose.rotation = glm::angleAxis(-0.6 * p_t, glm::normalize(glm::dvec3(0.0, 1.0, 0.1))) * start;
	pose.translation = glm::dvec3(2.0, 1.3, 1.0) + glm::dvec3(0.25, 0.0, -0.4) * p_t;
	return pose;
}

Trajectory rgb_trajectory(double p_start, double p_end, double p_step) {
	Trajectory trajectory;
	std::string error;
	for (double t = p_start; t <= p_end + 1e-9; t += p_step) {
		REQUIRE(trajectory.append({ t, rgb_motion_at(t) }, &error));
	}
	return trajectory;
}

Rig test_rig(double p_offset_s) {
	Rig rig;
	rig.rgb_from_fisheye.rotation = glm::normalize(glm::dquat(0.8, 0.5, -0.2, 0.1));
	rig.rgb_from_fisheye.translation = glm::dvec3(0.01, -0.08, 0.02);
	rig.fisheye_time_offset_s = p_offset_s;
	return rig;
}

} // namespace

TEST_CASE("fisheye_pose_at: equals world_from_rgb(t + offset) * rgb_from_fisheye") {
	const Trajectory trajectory = rgb_trajectory(0.0, 4.0, 1.0 / 30.0);
	const Rig rig = test_rig(0.0137);
	std::mt19937 rng(11);
	// Fisheye timestamps whose RGB-D time falls inside the trajectory.
	std::uniform_real_distribution<double> when(0.0 - 0.0137, trajectory.get_end_s() - 0.0137);
	for (int i = 0; i < 500; i++) {
		const double t_fisheye = when(rng);
		CAPTURE(t_fisheye);
		Pose world_from_fisheye;
		std::string error;
		REQUIRE(fisheye_pose_at(trajectory, rig, t_fisheye, &world_from_fisheye, &error));
		const Pose expected = compose(rgb_motion_at(t_fisheye + 0.0137), rig.rgb_from_fisheye);
		CHECK(rotation_distance(world_from_fisheye.rotation, expected.rotation) < 1e-9);
		CHECK(glm::length(world_from_fisheye.translation - expected.translation) < 1e-9);
		// The same, point by point: a point in the fisheye frame lands where the chain puts it.
		const glm::dvec3 x(0.3, -0.2, 2.0);
		const glm::dvec3 via_chain = transform_point(rgb_motion_at(t_fisheye + 0.0137), transform_point(rig.rgb_from_fisheye, x));
		CHECK(glm::length(transform_point(world_from_fisheye, x) - via_chain) < 1e-9);
	}
}

TEST_CASE("fisheye_pose_at: outside the trajectory, after the clock offset, it is an error") {
	const Trajectory trajectory = rgb_trajectory(10.0, 12.0, 0.05);
	const Rig rig = test_rig(0.0137);
	Pose untouched;
	untouched.translation = glm::dvec3(-7.0);
	// 12.0 - 0.005 is inside on the fisheye's clock but 12.0087 on the RGB-D clock: outside.
	for (const double t : { 9.0, 10.0 - 0.0137 - 1e-6, 12.0 - 0.005, 30.0 }) {
		CAPTURE(t);
		Pose pose = untouched;
		std::string error;
		CHECK_FALSE(fisheye_pose_at(trajectory, rig, t, &pose, &error));
		CHECK(pose.translation == untouched.translation);
		CHECK(contains(error, "outside the trajectory"));
		CHECK(contains(error, "RGB-D clock"));
	}
	// The first RGB-D sample, reached from the fisheye's clock.
	Pose pose;
	std::string error;
	REQUIRE(fisheye_pose_at(trajectory, rig, 10.0 - 0.0137, &pose, &error));
	const Pose expected = compose(rgb_motion_at(10.0), rig.rgb_from_fisheye);
	CHECK(rotation_distance(pose.rotation, expected.rotation) < 1e-12);
	CHECK(glm::length(pose.translation - expected.translation) < 1e-12);
	// A small extrapolation tolerance lets a frame just past the end through.
	REQUIRE(fisheye_pose_at(trajectory, rig, 12.0 - 0.005, &pose, &error, 0.01));
	const Pose extrapolated = compose(rgb_motion_at(12.0 - 0.005 + 0.0137), rig.rgb_from_fisheye);
	CHECK(glm::length(pose.translation - extrapolated.translation) < 1e-9);
}

TEST_CASE("fisheye_pose_at: the synthetic rig's upward fisheye looks at the ceiling") {
	// A level RGB-D camera looking along Godot's forward (-Z): camera x -> +X, y (down) -> -Y,
	// z -> -Z, a half turn about X.
	Trajectory trajectory;
	std::string error;
	Pose level;
	level.rotation = glm::dquat(0.0, 1.0, 0.0, 0.0);
	level.translation = glm::dvec3(1.0, 1.2, 3.0);
	REQUIRE(trajectory.set_samples({ { 0.0, level }, { 1.0, level } }, &error));
	Rig rig;
	const double h = std::sqrt(0.5);
	rig.rgb_from_fisheye.rotation = glm::dquat(h, h, 0.0, 0.0); // synthetic_rig.yaml's
	rig.rgb_from_fisheye.translation = glm::dvec3(0.0, -0.08, 0.02);
	rig.fisheye_time_offset_s = 0.0137;
	Pose world_from_fisheye;
	REQUIRE(fisheye_pose_at(trajectory, rig, 0.5, &world_from_fisheye, &error));
	// Optical axis up, image x along the RGB camera's x, the fisheye 8 cm above and 2 cm ahead.
	CHECK(glm::length(world_from_fisheye.rotation * glm::dvec3(0, 0, 1) - glm::dvec3(0, 1, 0)) < 1e-12);
	CHECK(glm::length(world_from_fisheye.rotation * glm::dvec3(1, 0, 0) - glm::dvec3(1, 0, 0)) < 1e-12);
	CHECK(glm::length(world_from_fisheye.translation - glm::dvec3(1.0, 1.28, 2.98)) < 1e-12);
}
