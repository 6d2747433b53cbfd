#pragma once
// Rigid poses, and their interpolation between two timestamps (paper §4.3).
//
// Conventions, used everywhere in the core:
// - World: Y up, metres (Godot's). The floorplan (x, z) lies on the plane y = 0.
// - Camera frames: OpenCV's, x right, y down, z forward (optical axis), metres.
// - A Pose named a_from_b maps points of frame b into frame a: x_a = rotation * x_b + translation.
//   A camera's pose is world_from_camera.

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace roomprobe {

struct Pose {
	glm::dquat rotation = glm::dquat(1.0, 0.0, 0.0, 0.0); // unit quaternion (w, x, y, z)
	glm::dvec3 translation = glm::dvec3(0.0); // metres
};

// x_a = p_pose * x_b.
glm::dvec3 transform_point(const Pose &p_pose, const glm::dvec3 &p_point);
// a_from_c = a_from_b * b_from_c.
Pose compose(const Pose &p_a_from_b, const Pose &p_b_from_c);
Pose inverse(const Pose &p_pose);
// Translation by lerp and rotation by slerp (shortest arc), as §4.3 does between the two
// RGB-D poses nearest the fisheye's timestamp; p_alpha = 0 gives p_from, 1 gives p_to.
Pose interpolate(const Pose &p_from, const Pose &p_to, double p_alpha);

// The 4x4 homogeneous matrix of a pose (column-major, glm's), and back. pose_from_matrix expects
// a rotation in the upper-left 3x3 and the translation in column 3; the bottom row is ignored.
glm::dmat4 pose_to_matrix(const Pose &p_pose);
Pose pose_from_matrix(const glm::dmat4 &p_matrix);

// A rotation vector (axis times angle in radians, cv::Rodrigues' convention) and back: the
// minimal parameters of a pose for the least-squares fits.
glm::dquat rotation_from_vector(const glm::dvec3 &p_rotation_vector);
glm::dvec3 rotation_vector(const glm::dquat &p_rotation);

// Whether every component of the pose is finite.
bool is_finite(const Pose &p_pose);
// Scales r_rotation to unit norm when its norm is within p_tolerance of 1 (files store rounded
// quaternions); returns false, leaving it unchanged, otherwise (or when it is not finite).
bool normalize_rotation(glm::dquat *r_rotation, double p_tolerance);

} // namespace roomprobe
