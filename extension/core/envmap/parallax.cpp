#include "parallax.h"

#include <glm/geometric.hpp>

#include <cmath>

namespace roomprobe {

double sample_distance(const Cubemap &p_map, const glm::dvec3 &p_direction) {
	if (!has_distances(p_map)) {
		return 0.0;
	}
	const CubemapBilinear taps = cubemap_bilinear(p_direction, p_map.size);
	const cv::Mat &face = p_map.distance_m[size_t(taps.face)];
	double distance = 0.0;
	for (int i = 0; i < 4; i++) {
		distance += taps.weight[size_t(i)] * double(face.at<float>(taps.y[size_t(i)], taps.x[size_t(i)]));
	}
	return distance;
}

glm::dvec3 parallax_direction(const Cubemap &p_map, const glm::dvec3 &p_centre, const glm::dvec3 &p_point, const glm::dvec3 &p_direction, int p_iterations) {
	const glm::dvec3 r = glm::normalize(p_direction);
	const glm::dvec3 o = p_point - p_centre;
	const double d_r = sample_distance(p_map, r);
	const double o_length = glm::length(o);
	// At the centre the ray is the map's own; nothing known along it, or a point beyond it: as is.
	if (!(d_r > 0.0) || o_length < 1e-6) {
		return r;
	}
	// f(t) = D(towards o + t r) - |o + t r|: positive before the surface, negative beyond.
	auto f = [&](double p_t) {
		const glm::dvec3 x = o + p_t * r;
		return sample_distance(p_map, x) - glm::length(x);
	};
	double t_lo = 0.0, f_lo = f(0.0);
	if (!(f_lo > 0.0)) {
		return r;
	}
	// The first guess: where the ray leaves the sphere of radius D(r) (exact for a spherical room),
	// doubled until the point lies beyond the surface.
	const double b = glm::dot(o, r), discriminant = b * b - (o_length * o_length - d_r * d_r);
	// A point outside that sphere (near a wall the ray leaves the room) may give no root, or a
	// tiny one: then D(r) itself, the scale of the room in that direction.
	const double guess = discriminant > 0.0 ? -b + std::sqrt(discriminant) : 0.0;
	double t_hi = guess > 0.05 * d_r ? guess : d_r;
	double f_hi = f(t_hi);
	for (int k = 0; k < PARALLAX_EXPANSIONS && f_hi > 0.0; k++) {
		t_lo = t_hi;
		f_lo = f_hi;
		t_hi *= 2.0;
		f_hi = f(t_hi);
	}
	if (f_hi > 0.0) {
		return o + t_hi * r; // no surface found within reach: the farthest point tried
	}
	// Regula falsi, Illinois variant: the end kept twice in a row has its value halved.
	double t = t_hi;
	int kept = 0;
	for (int i = 0; i < p_iterations; i++) {
		t = t_lo + (t_hi - t_lo) * f_lo / (f_lo - f_hi);
		const double f_t = f(t);
		if (f_t > 0.0) {
			t_lo = t;
			f_lo = f_t;
			f_hi *= kept == -1 ? 0.5 : 1.0;
			kept = -1;
		} else {
			t_hi = t;
			f_hi = f_t;
			f_lo *= kept == 1 ? 0.5 : 1.0;
			kept = 1;
		}
	}
	return o + t * r;
}

} // namespace roomprobe
