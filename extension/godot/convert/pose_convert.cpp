#include "pose_convert.h"

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

using namespace godot;

namespace roomprobe {

Vector3 to_godot(const glm::dvec3 &p_v) {
	return Vector3(real_t(p_v.x), real_t(p_v.y), real_t(p_v.z));
}

glm::dvec3 to_glm(const Vector3 &p_v) {
	return glm::dvec3(p_v.x, p_v.y, p_v.z);
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

} // namespace roomprobe
