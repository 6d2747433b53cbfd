#pragma once
// Poses between the core (math/pose.h: OpenCV camera frames, x right, y down, z forward) and
// Godot (Transform3D; a Camera3D looks down -Z with Y up). World frames agree: Y up, metres.

#include <math/pose.h>

#include <rp_godot/godot.h>

namespace roomprobe {

// A camera's world_from_camera as the transform of a Camera3D that sees what it sees.
godot::Transform3D camera_transform_from_pose(const Pose &p_world_from_camera);
// The inverse.
Pose pose_from_camera_transform(const godot::Transform3D &p_transform);

godot::Vector3 to_godot(const glm::dvec3 &p_v);
glm::dvec3 to_glm(const godot::Vector3 &p_v);

} // namespace roomprobe
