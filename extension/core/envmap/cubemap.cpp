#include "cubemap.h"

#include <algorithm>
#include <cmath>
#include <cstring>

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
		out.distance_m[f] = p_cubemap.distance_m[f].clone();
	}
	return out;
}

bool same_pixels(const cv::Mat &p_a, const cv::Mat &p_b) {
	if (p_a.size() != p_b.size() || p_a.type() != p_b.type()) {
		return false;
	}
	const size_t row_bytes = size_t(p_a.cols) * p_a.elemSize();
	for (int y = 0; y < p_a.rows && p_a.data != p_b.data; y++) {
		if (std::memcmp(p_a.ptr(y), p_b.ptr(y), row_bytes) != 0) {
			return false;
		}
	}
	return true;
}

uint8_t cubemap_changed_faces(const Cubemap &p_a, const Cubemap &p_b) {
	if (!is_valid_cubemap(p_a) || !is_valid_cubemap(p_b) || p_a.size != p_b.size) {
		return 0x3F;
	}
	uint8_t changed = 0;
	for (int f = 0; f < 6; f++) {
		if (!same_pixels(p_a.faces[size_t(f)], p_b.faces[size_t(f)])) {
			changed |= uint8_t(1u << f);
		}
	}
	return changed;
}

bool has_distances(const Cubemap &p_cubemap) {
	for (const cv::Mat &face : p_cubemap.distance_m) {
		if (face.type() != CV_32FC1 || face.rows != p_cubemap.size || face.cols != p_cubemap.size) {
			return false;
		}
	}
	return p_cubemap.size > 0;
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

CubemapBilinear cubemap_bilinear(const glm::dvec3 &p_direction, int p_size) {
	CubemapBilinear read;
	double u = 0.0, v = 0.0;
	cubemap_face_pixel(p_direction, p_size, &read.face, &u, &v);
	const int n = p_size;
	u = std::clamp(u, 0.0, double(n - 1));
	v = std::clamp(v, 0.0, double(n - 1));
	const int x0 = std::min(int(u), n - 1), y0 = std::min(int(v), n - 1);
	const int x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
	const double fx = u - x0, fy = v - y0;
	read.x = { x0, x1, x0, x1 };
	read.y = { y0, y0, y1, y1 };
	read.weight = { (1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy };
	return read;
}

glm::dvec3 sample_cubemap(const Cubemap &p_cubemap, const glm::dvec3 &p_direction) {
	const CubemapBilinear read = cubemap_bilinear(p_direction, p_cubemap.size);
	const cv::Mat &image = p_cubemap.faces[size_t(read.face)];
	glm::dvec3 sum(0.0);
	for (int k = 0; k < 4; k++) {
		const cv::Vec3f &c = image.at<cv::Vec3f>(read.y[size_t(k)], read.x[size_t(k)]);
		sum += read.weight[size_t(k)] * glm::dvec3(c[0], c[1], c[2]);
	}
	return sum;
}

} // namespace roomprobe
