#pragma once
// Poses between the core (math/pose.h: OpenCV camera frames, x right, y down, z forward) and
// Godot (Transform3D; a Camera3D looks down -Z with Y up). World frames agree: Y up, metres.

#include <math/pose.h>

#include <glm/mat3x3.hpp>

#include <rp_godot/godot.h>

namespace roomprobe {

// A camera's world_from_camera as the transform of a Camera3D that sees what it sees.
godot::Transform3D camera_transform_from_pose(const Pose &p_world_from_camera);
// The inverse.
Pose pose_from_camera_transform(const godot::Transform3D &p_transform);

// A rigid frame (a node's transform: no camera axes flipped) and back. pose_from_transform drops
// scale and shear (rotation_from_basis); false for a degenerate or non-finite transform.
godot::Transform3D transform_from_pose(const Pose &p_a_from_b);
bool pose_from_transform(const godot::Transform3D &p_transform, Pose *r_pose);

godot::Vector3 to_godot(const glm::dvec3 &p_v);
glm::dvec3 to_glm(const godot::Vector3 &p_v);
// The basis as a matrix whose columns are its axes (glm's m[column][row]).
glm::dmat3 to_glm(const godot::Basis &p_basis);
godot::Basis to_godot(const glm::dmat3 &p_matrix); // the inverse of to_glm
// The rotation of p_basis: its columns (the frame's axes in world coordinates) orthonormalised
// (Gram-Schmidt), so scale and shear drop out. False for a degenerate or non-finite basis.
bool rotation_from_basis(const godot::Basis &p_basis, glm::dmat3 *r_rotation);

} // namespace roomprobe
