#include "ggx_prefilter.h"

#include <recording/cubemap_layout.h>

#include <glm/geometric.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace roomprobe {

namespace {

constexpr double PI = std::numbers::pi;

// GGX's normal distribution, alpha = roughness^2.
double ggx_d(double p_cos_h, double p_alpha) {
	const double a2 = p_alpha * p_alpha;
	const double d = p_cos_h * p_cos_h * (a2 - 1.0) + 1.0;
	return a2 / (PI * d * d);
}

// A face texel's value, bilinear, clamped at the face's edges.
glm::dvec3 sample_face(const cv::Mat &p_face, double p_u, double p_v) {
	const int n = p_face.cols;
	const double u = std::clamp(p_u, 0.0, double(n - 1)), v = std::clamp(p_v, 0.0, double(n - 1));
	const int x0 = std::min(int(u), n - 1), y0 = std::min(int(v), n - 1);
	const int x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
	const double fx = u - x0, fy = v - y0;
	const auto at = [&](int p_x, int p_y) {
		const cv::Vec3f &c = p_face.at<cv::Vec3f>(p_y, p_x);
		return glm::dvec3(c[0], c[1], c[2]);
	};
	return (at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx) * (1.0 - fy) + (at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx) * fy;
}

glm::dvec3 sample_cubemap(const Cubemap &p_map, const glm::dvec3 &p_direction) {
	int face = 0;
	double u = 0.0, v = 0.0;
	cubemap_face_pixel(p_direction, p_map.size, &face, &u, &v);
	return sample_face(p_map.faces[size_t(face)], u, v);
}

// The source and its box-filtered halvings down to 1 texel a face.
std::vector<Cubemap> box_pyramid(const Cubemap &p_source) {
	std::vector<Cubemap> pyramid{ p_source };
	while (pyramid.back().size > 1) {
		const Cubemap &above = pyramid.back();
		Cubemap next;
		next.size = std::max(1, above.size / 2);
		for (int f = 0; f < 6; f++) {
			cv::resize(above.faces[size_t(f)], next.faces[size_t(f)], cv::Size(next.size, next.size), 0.0, 0.0, cv::INTER_AREA);
		}
		pyramid.push_back(next);
	}
	return pyramid;
}

double radical_inverse(uint32_t p_bits) {
	p_bits = (p_bits << 16u) | (p_bits >> 16u);
	p_bits = ((p_bits & 0x55555555u) << 1u) | ((p_bits & 0xAAAAAAAAu) >> 1u);
	p_bits = ((p_bits & 0x33333333u) << 2u) | ((p_bits & 0xCCCCCCCCu) >> 2u);
	p_bits = ((p_bits & 0x0F0F0F0Fu) << 4u) | ((p_bits & 0xF0F0F0F0u) >> 4u);
	p_bits = ((p_bits & 0x00FF00FFu) << 8u) | ((p_bits & 0xFF00FF00u) >> 8u);
	return double(p_bits) * 2.3283064365386963e-10;
}

} // namespace

double ggx_level_roughness(int p_level, int p_levels) {
	return p_levels <= 1 ? 0.0 : double(p_level) / double(p_levels - 1);
}

std::vector<Cubemap> prefilter_ggx(const Cubemap &p_source, const GgxPrefilterOptions &p_options) {
	std::vector<Cubemap> chain;
	if (!is_valid_cubemap(p_source) || p_options.levels < 1 || p_options.samples < 1) {
		return chain;
	}
	const std::vector<Cubemap> pyramid = box_pyramid(p_source);
	chain.push_back(clone_cubemap(p_source));
	const int samples = p_options.samples;
	// The source texel's solid angle at level 0 (about; the cube's texels vary by 5x).
	const double texel_solid_angle = 4.0 * PI / (6.0 * double(p_source.size) * double(p_source.size));
	for (int level = 1; level < p_options.levels; level++) {
		const double roughness = ggx_level_roughness(level, p_options.levels);
		const double alpha = roughness * roughness;
		const int size = std::max(1, p_source.size >> level);
		Cubemap out = make_cubemap(size);
		tbb::parallel_for(0, 6 * size, [&](int p_row) {
			const int face = p_row / size, y = p_row % size;
			cv::Vec3f *row = out.faces[size_t(face)].ptr<cv::Vec3f>(y);
			for (int x = 0; x < size; x++) {
				const glm::dvec3 r = cubemap_direction(face, x, y, size);
				// A frame around R.
				const glm::dvec3 helper = std::abs(r.z) < 0.999 ? glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(1.0, 0.0, 0.0);
				const glm::dvec3 t = glm::normalize(glm::cross(helper, r));
				const glm::dvec3 b = glm::cross(r, t);
				glm::dvec3 sum(0.0);
				double weight = 0.0;
				for (int s = 0; s < samples; s++) {
					const double u1 = (s + 0.5) / samples, u2 = radical_inverse(uint32_t(s));
					// h from D(h) (n . h): cos^2 = (1 - u) / (1 + (a^2 - 1) u).
					const double cos_h = std::sqrt((1.0 - u1) / (1.0 + (alpha * alpha - 1.0) * u1));
					const double sin_h = std::sqrt(std::max(0.0, 1.0 - cos_h * cos_h));
					const double phi = 2.0 * PI * u2;
					const glm::dvec3 h = sin_h * std::cos(phi) * t + sin_h * std::sin(phi) * b + cos_h * r;
					const glm::dvec3 l = 2.0 * glm::dot(r, h) * h - r;
					const double r_dot_l = glm::dot(r, l);
					if (r_dot_l <= 0.0) {
						continue;
					}
					// pdf of l: D(h) (n . h) / (4 (l . h)) = D(h) / 4 with n = v = R.
					const double pdf = ggx_d(cos_h, alpha) / 4.0;
					const double sample_solid_angle = 1.0 / (double(samples) * pdf);
					const double lod = std::clamp(0.5 * std::log2(sample_solid_angle / texel_solid_angle) + 1.0, 0.0, double(pyramid.size() - 1));
					const int l0 = int(lod);
					const int l1 = std::min(l0 + 1, int(pyramid.size()) - 1);
					const double f = lod - l0;
					const glm::dvec3 value = sample_cubemap(pyramid[size_t(l0)], l) * (1.0 - f) + sample_cubemap(pyramid[size_t(l1)], l) * f;
					sum += value * r_dot_l;
					weight += r_dot_l;
				}
				const glm::dvec3 c = weight > 0.0 ? sum / weight : sample_cubemap(p_source, r);
				row[x] = cv::Vec3f(float(c.x), float(c.y), float(c.z));
			}
		});
		chain.push_back(out);
	}
	return chain;
}

Cubemap ggx_reference(const Cubemap &p_source, double p_roughness, int p_size) {
	Cubemap out = make_cubemap(p_size);
	if (!is_valid_cubemap(p_source) || p_size < 1) {
		return out;
	}
	const double alpha = std::max(p_roughness * p_roughness, 1e-4);
	const int n = p_source.size;
	std::vector<glm::dvec3> directions, values;
	std::vector<double> solid_angles;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < n; y++) {
			for (int x = 0; x < n; x++) {
				directions.push_back(cubemap_direction(f, x, y, n));
				const cv::Vec3f &c = p_source.faces[size_t(f)].at<cv::Vec3f>(y, x);
				values.emplace_back(c[0], c[1], c[2]);
				solid_angles.push_back(cubemap_texel_solid_angle(x, y, n));
			}
		}
	}
	tbb::parallel_for(0, 6 * p_size, [&](int p_row) {
		const int face = p_row / p_size, y = p_row % p_size;
		cv::Vec3f *row = out.faces[size_t(face)].ptr<cv::Vec3f>(y);
		for (int x = 0; x < p_size; x++) {
			const glm::dvec3 r = cubemap_direction(face, x, y, p_size);
			glm::dvec3 sum(0.0);
			double weight = 0.0;
			for (size_t i = 0; i < directions.size(); i++) {
				const double r_dot_l = glm::dot(r, directions[i]);
				if (r_dot_l <= 0.0) {
					continue;
				}
				const glm::dvec3 h = glm::normalize(r + directions[i]);
				const double w = ggx_d(glm::dot(r, h), alpha) * r_dot_l * solid_angles[i];
				sum += values[i] * w;
				weight += w;
			}
			const glm::dvec3 c = weight > 0.0 ? sum / weight : glm::dvec3(0.0);
			row[x] = cv::Vec3f(float(c.x), float(c.y), float(c.z));
		}
	});
	return out;
}

} // namespace roomprobe
