#include "pose.h"

#include <glm/gtc/quaternion.hpp>

#include <cmath>

namespace roomprobe {

glm::dvec3 transform_point(const Pose &p_pose, const glm::dvec3 &p_point) {
	return p_pose.rotation * p_point + p_pose.translation;
}

Pose compose(const Pose &p_a_from_b, const Pose &p_b_from_c) {
	Pose a_from_c;
	// Renormalised so that long chains of compositions do not drift off the unit sphere.
	a_from_c.rotation = glm::normalize(p_a_from_b.rotation * p_b_from_c.rotation);
	a_from_c.translation = p_a_from_b.rotation * p_b_from_c.translation + p_a_from_b.translation;
	return a_from_c;
}

Pose inverse(const Pose &p_pose) {
	Pose b_from_a;
	b_from_a.rotation = glm::conjugate(p_pose.rotation);
	b_from_a.translation = -(b_from_a.rotation * p_pose.translation);
	return b_from_a;
}

namespace {

// Slerp along the shorter arc. Written out rather than glm::slerp so the angle comes from atan2
// (accurate for the tiny angles between consecutive frames, where acos loses digits) and so
// p_alpha outside [0, 1] extrapolates along the same great circle at the same rate.
glm::dquat slerp_shortest(const glm::dquat &p_from, glm::dquat p_to, double p_alpha) {
	double cos_angle = glm::dot(p_from, p_to);
	// q and -q are the same rotation; flipping p_to onto p_from's hemisphere takes the short way.
	if (cos_angle < 0.0) {
		p_to = -p_to;
		cos_angle = -cos_angle;
	}
	const double sin_angle = glm::length(p_to - p_from * cos_angle);
	const double angle = std::atan2(sin_angle, cos_angle); // half the rotation angle between them
	if (sin_angle < 1e-12) {
		// Nearly the same rotation: slerp's weights tend to lerp's, and dividing would lose digits.
		return glm::normalize(p_from * (1.0 - p_alpha) + p_to * p_alpha);
	}
	const double w_from = std::sin((1.0 - p_alpha) * angle) / sin_angle;
	const double w_to = std::sin(p_alpha * angle) / sin_angle;
	return glm::normalize(p_from * w_from + p_to * w_to);
}

} // namespace

Pose interpolate(const Pose &p_from, const Pose &p_to, double p_alpha) {
	Pose pose;
	// Exact endpoints, not merely close ones, so a timestamp equal to a sample returns that sample.
	if (p_alpha == 0.0) {
		return p_from;
	}
	if (p_alpha == 1.0) {
		return p_to;
	}
	pose.rotation = slerp_shortest(p_from.rotation, p_to.rotation, p_alpha);
	pose.translation = p_from.translation + (p_to.translation - p_from.translation) * p_alpha;
	return pose;
}

glm::dmat4 pose_to_matrix(const Pose &p_pose) {
	glm::dmat4 matrix = glm::mat4_cast(p_pose.rotation);
	matrix[3] = glm::dvec4(p_pose.translation, 1.0);
	return matrix;
}

Pose pose_from_matrix(const glm::dmat4 &p_matrix) {
	Pose pose;
	pose.rotation = glm::normalize(glm::quat_cast(glm::dmat3(p_matrix)));
	pose.translation = glm::dvec3(p_matrix[3]);
	return pose;
}

bool is_finite(const Pose &p_pose) {
	const glm::dquat &q = p_pose.rotation;
	const glm::dvec3 &t = p_pose.translation;
	return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) &&
			std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z);
}

bool normalize_rotation(glm::dquat *r_rotation, double p_tolerance) {
	const double norm = glm::length(*r_rotation);
	if (!std::isfinite(norm) || !(std::abs(norm - 1.0) <= p_tolerance)) {
		return false;
	}
	*r_rotation = *r_rotation / norm;
	return true;
}

glm::dquat rotation_from_vector(const glm::dvec3 &p_rotation_vector) {
	const double angle = glm::length(p_rotation_vector);
	if (angle < 1e-12) {
		// First order: q = (1, v / 2), normalised.
		return glm::normalize(glm::dquat(1.0, 0.5 * p_rotation_vector.x, 0.5 * p_rotation_vector.y, 0.5 * p_rotation_vector.z));
	}
	return glm::angleAxis(angle, p_rotation_vector / angle);
}

glm::dvec3 rotation_vector(const glm::dquat &p_rotation) {
	glm::dquat q = glm::normalize(p_rotation);
	if (q.w < 0.0) {
		q = -q; // the shorter way round: angle in [0, pi]
	}
	const glm::dvec3 axis(q.x, q.y, q.z);
	const double s = glm::length(axis);
	if (s < 1e-12) {
		return 2.0 * axis;
	}
	return axis * (2.0 * std::atan2(s, q.w) / s);
}

} // namespace roomprobe
