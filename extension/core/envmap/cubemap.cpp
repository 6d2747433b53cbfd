#include "cubemap.h"

#include <cmath>

namespace roomprobe {

Cubemap make_cubemap(int p_size, const cv::Vec3f &p_fill) {
	Cubemap cubemap;
	cubemap.size = p_size;
	for (cv::Mat &face : cubemap.faces) {
		face = cv::Mat(p_size, p_size, CV_32FC3, cv::Scalar(p_fill[0], p_fill[1], p_fill[2]));
	}
	return cubemap;
}

Cubemap clone_cubemap(const Cubemap &p_cubemap) {
	Cubemap out;
	out.size = p_cubemap.size;
	for (size_t f = 0; f < 6; f++) {
		out.faces[f] = p_cubemap.faces[f].clone();
	}
	return out;
}

bool is_valid_cubemap(const Cubemap &p_cubemap) {
	if (p_cubemap.size <= 0) {
		return false;
	}
	for (const cv::Mat &face : p_cubemap.faces) {
		if (face.type() != CV_32FC3 || face.rows != p_cubemap.size || face.cols != p_cubemap.size) {
			return false;
		}
	}
	return true;
}

namespace {

// Solid angle of the face region from the face centre to (p_s, p_t) on the unit-distance face
// plane (Girard / Manne's formula): atan2(s t, sqrt(s^2 + t^2 + 1)).
double corner_area(double p_s, double p_t) {
	return std::atan2(p_s * p_t, std::sqrt(p_s * p_s + p_t * p_t + 1.0));
}

} // namespace

double cubemap_texel_solid_angle(int p_u, int p_v, int p_size) {
	const double n = double(p_size);
	const double s0 = 2.0 * p_u / n - 1.0;
	const double s1 = 2.0 * (p_u + 1) / n - 1.0;
	const double t0 = 2.0 * p_v / n - 1.0;
	const double t1 = 2.0 * (p_v + 1) / n - 1.0;
	return corner_area(s0, t0) - corner_area(s0, t1) - corner_area(s1, t0) + corner_area(s1, t1);
}

} // namespace roomprobe
