#include "pose_convert.h"

#include <glm/gtc/quaternion.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <cmath>

using namespace godot;

namespace roomprobe {

Vector3 to_godot(const glm::dvec3 &p_v) {
	return Vector3(real_t(p_v.x), real_t(p_v.y), real_t(p_v.z));
}

glm::dvec3 to_glm(const Vector3 &p_v) {
	return glm::dvec3(p_v.x, p_v.y, p_v.z);
}

glm::dmat3 to_glm(const Basis &p_basis) {
	glm::dmat3 m;
	for (int row = 0; row < 3; row++) {
		const glm::dvec3 r = to_glm(p_basis.rows[row]);
		for (int column = 0; column < 3; column++) {
			m[column][row] = r[column];
		}
	}
	return m;
}

Basis to_godot(const glm::dmat3 &p_matrix) {
	Basis b;
	for (int row = 0; row < 3; row++) {
		b.rows[row] = Vector3(real_t(p_matrix[0][row]), real_t(p_matrix[1][row]), real_t(p_matrix[2][row]));
	}
	return b;
}

Transform3D camera_transform_from_pose(const Pose &p_world_from_camera) {
	// Godot's basis columns are the camera's axes in the world: x, -y, -z of OpenCV's.
	const glm::dmat3 r = glm::mat3_cast(p_world_from_camera.rotation); // glm: r[column][row]
	Transform3D t;
	for (int row = 0; row < 3; row++) {
		t.basis.rows[row] = Vector3(real_t(r[0][row]), real_t(-r[1][row]), real_t(-r[2][row]));
	}
	t.origin = to_godot(p_world_from_camera.translation);
	return t;
}

Pose pose_from_camera_transform(const Transform3D &p_transform) {
	glm::dmat3 r;
	for (int row = 0; row < 3; row++) {
		const Vector3 &b = p_transform.basis.rows[row];
		r[0][row] = b.x;
		r[1][row] = -b.y;
		r[2][row] = -b.z;
	}
	Pose pose;
	pose.rotation = glm::normalize(glm::quat_cast(r));
	pose.translation = to_glm(p_transform.origin);
	return pose;
}

Transform3D transform_from_pose(const Pose &p_a_from_b) {
	const glm::dmat3 r = glm::mat3_cast(p_a_from_b.rotation); // glm: r[column][row]
	Transform3D t;
	for (int row = 0; row < 3; row++) {
		t.basis.rows[row] = Vector3(real_t(r[0][row]), real_t(r[1][row]), real_t(r[2][row]));
	}
	t.origin = to_godot(p_a_from_b.translation);
	return t;
}

bool pose_from_transform(const Transform3D &p_transform, Pose *r_pose) {
	glm::dmat3 r;
	if (!rotation_from_basis(p_transform.basis, &r) || glm::determinant(r) < 0.0 || !std::isfinite(p_transform.origin.x) || !std::isfinite(p_transform.origin.y) ||
			!std::isfinite(p_transform.origin.z)) {
		return false;
	}
	r_pose->rotation = glm::normalize(glm::quat_cast(r));
	r_pose->translation = to_glm(p_transform.origin);
	return true;
}

bool rotation_from_basis(const godot::Basis &p_basis, glm::dmat3 *r_rotation) {
	const glm::dmat3 m = to_glm(p_basis);
	const glm::dvec3 axes[3] = { m[0], m[1], m[2] };
	const double volume = glm::dot(axes[0], glm::cross(axes[1], axes[2]));
	if (!std::isfinite(volume) || std::abs(volume) < 1e-12) {
		return false;
	}
	const glm::dvec3 x = glm::normalize(axes[0]);
	const glm::dvec3 y = glm::normalize(axes[1] - glm::dot(axes[1], x) * x);
	const glm::dvec3 z = glm::cross(x, y) * (volume > 0.0 ? 1.0 : -1.0);
	*r_rotation = glm::dmat3(x, y, z);
	return true;
}

} // namespace roomprobe
