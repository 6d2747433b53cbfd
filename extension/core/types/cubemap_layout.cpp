#include "cubemap_layout.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace roomprobe {

const char *cubemap_face_name(int p_face) {
	static const char *const names[6] = { "+X", "-X", "+Y", "-Y", "+Z", "-Z" };
	return p_face >= 0 && p_face < 6 ? names[p_face] : "?";
}

glm::dvec3 cubemap_direction(int p_face, double p_u, double p_v, int p_size) {
	const double n = p_size > 0 ? double(p_size) : 1.0;
	const double s = 2.0 * (p_u + 0.5) / n - 1.0;
	const double t = 2.0 * (p_v + 0.5) / n - 1.0;
	glm::dvec3 direction(0.0);
	switch (p_face) {
		case CUBEMAP_POSITIVE_X:
			direction = glm::dvec3(1.0, -t, -s);
			break;
		case CUBEMAP_NEGATIVE_X:
			direction = glm::dvec3(-1.0, -t, s);
			break;
		case CUBEMAP_POSITIVE_Y:
			direction = glm::dvec3(s, 1.0, t);
			break;
		case CUBEMAP_NEGATIVE_Y:
			direction = glm::dvec3(s, -1.0, -t);
			break;
		case CUBEMAP_POSITIVE_Z:
			direction = glm::dvec3(s, -t, 1.0);
			break;
		case CUBEMAP_NEGATIVE_Z:
			direction = glm::dvec3(-s, -t, -1.0);
			break;
		default:
			return glm::dvec3(0.0);
	}
	return glm::normalize(direction);
}

void cubemap_face_pixel(const glm::dvec3 &p_direction, int p_size, int *r_face, double *r_u, double *r_v) {
	const double ax = std::abs(p_direction.x);
	const double ay = std::abs(p_direction.y);
	const double az = std::abs(p_direction.z);
	int face = CUBEMAP_POSITIVE_X;
	double s = 0.0;
	double t = 0.0;
	if (ax >= ay && ax >= az && ax > 0.0) {
		face = p_direction.x > 0.0 ? CUBEMAP_POSITIVE_X : CUBEMAP_NEGATIVE_X;
		s = (p_direction.x > 0.0 ? -p_direction.z : p_direction.z) / ax;
		t = -p_direction.y / ax;
	} else if (ay >= az && ay > 0.0) {
		face = p_direction.y > 0.0 ? CUBEMAP_POSITIVE_Y : CUBEMAP_NEGATIVE_Y;
		s = p_direction.x / ay;
		t = (p_direction.y > 0.0 ? p_direction.z : -p_direction.z) / ay;
	} else if (az > 0.0) {
		face = p_direction.z > 0.0 ? CUBEMAP_POSITIVE_Z : CUBEMAP_NEGATIVE_Z;
		s = (p_direction.z > 0.0 ? p_direction.x : -p_direction.x) / az;
		t = -p_direction.y / az;
	}
	const double n = double(p_size);
	*r_face = face;
	*r_u = (s + 1.0) * 0.5 * n - 0.5;
	*r_v = (t + 1.0) * 0.5 * n - 0.5;
}

cv::Mat cubemap_faces_to_strip(const CubemapFaces &p_faces) {
	const cv::Mat &first = p_faces[0];
	if (first.empty() || first.rows != first.cols) {
		return cv::Mat();
	}
	for (const cv::Mat &face : p_faces) {
		if (face.size() != first.size() || face.type() != first.type()) {
			return cv::Mat();
		}
	}
	const int n = first.cols;
	cv::Mat strip(6 * n, n, first.type());
	for (int f = 0; f < 6; f++) {
		p_faces[f].copyTo(strip.rowRange(f * n, (f + 1) * n));
	}
	return strip;
}

CubemapFaces cubemap_strip_to_faces(const cv::Mat &p_strip) {
	CubemapFaces faces;
	const int n = p_strip.cols;
	if (p_strip.empty() || p_strip.rows != 6 * n) {
		return faces;
	}
	for (int f = 0; f < 6; f++) {
		faces[f] = p_strip.rowRange(f * n, (f + 1) * n).clone();
	}
	return faces;
}

} // namespace roomprobe
