#include "mirror_error.h"
#include "metrics.h"

#include <envmap/parallax.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <vector>

namespace roomprobe {

namespace {

constexpr double VIEWER_DISTANCE_M = 1.5;

} // namespace

MirrorScores mirror_sphere_error(const synth::SynthRenderer &p_scene, const Cubemap &p_map, const glm::dvec3 &p_centre, double p_radius_m, double p_time_s,
		int p_image_size) {
	MirrorScores scores;
	std::vector<cv::Vec3f> reference, plain, parallax;
	const glm::dvec3 up(0.0, 1.0, 0.0);
	const glm::dvec3 sides[4] = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 0, 1 }, { 0, 0, -1 } };
	// The sphere fills 90 % of the image's height.
	const double half_angle = std::asin(std::min(1.0, p_radius_m / VIEWER_DISTANCE_M)) / 0.9;
	const double focal = 0.5 * p_image_size / std::tan(half_angle);
	const double c = 0.5 * (p_image_size - 1);
	for (const glm::dvec3 &side : sides) {
		const glm::dvec3 eye = p_centre + VIEWER_DISTANCE_M * side;
		if (p_scene.occluded(p_centre, side, p_radius_m, VIEWER_DISTANCE_M)) {
			continue;
		}
		scores.views++;
		const glm::dvec3 forward = -side, right = glm::normalize(glm::cross(forward, up)), down = glm::cross(forward, right);
		const glm::dvec3 o = eye - p_centre;
		for (int v = 0; v < p_image_size; v++) {
			for (int u = 0; u < p_image_size; u++) {
				const glm::dvec3 ray = glm::normalize(forward + ((u - c) / focal) * right + ((v - c) / focal) * down);
				// The ray's first point on the sphere.
				const double b = glm::dot(o, ray), discriminant = b * b - (glm::dot(o, o) - p_radius_m * p_radius_m);
				if (discriminant <= 0.0) {
					continue;
				}
				const glm::dvec3 point = eye + (-b - std::sqrt(discriminant)) * ray;
				const glm::dvec3 normal = glm::normalize(point - p_centre);
				const glm::dvec3 reflected = ray - 2.0 * glm::dot(ray, normal) * normal;
				const synth::Color truth = p_scene.radiance(point + 1e-5 * normal, reflected, p_time_s);
				reference.emplace_back(truth.x, truth.y, truth.z);
				const glm::dvec3 a = sample_cubemap(p_map, reflected);
				const glm::dvec3 d = sample_cubemap(p_map, parallax_direction(p_map, p_centre, point, reflected));
				plain.emplace_back(float(a.x), float(a.y), float(a.z));
				parallax.emplace_back(float(d.x), float(d.y), float(d.z));
			}
		}
	}
	scores.pixels = reference.size();
	if (reference.empty()) {
		return scores;
	}
	auto tone_mapped = [](std::vector<cv::Vec3f> &p_values) { return tone_map_face(cv::Mat(int(p_values.size()), 1, CV_32FC3, p_values.data())); };
	const cv::Mat truth8 = tone_mapped(reference);
	scores.psnr_plain_db = psnr_8bit({ tone_mapped(plain) }, { truth8 });
	scores.psnr_parallax_db = psnr_8bit({ tone_mapped(parallax) }, { truth8 });
	return scores;
}

} // namespace roomprobe
