#include "rgb_texture_update.h"

#include <camera/pinhole_camera.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace roomprobe {

namespace {

// Whether any part of a tile's bounding sphere can be in front of the camera and in its image
// (the image rectangle widened by the sphere's radius at its depth).
bool tile_in_view(const glm::dvec3 &p_centre_camera, double p_radius, const PinholeParams &p_camera) {
	if (p_radius < 0.0 || p_centre_camera.z + p_radius <= 0.05) {
		return false;
	}
	const double z = std::max(p_centre_camera.z, 0.05);
	const double margin_x = p_radius * p_camera.fx / z, margin_y = p_radius * p_camera.fy / z;
	const double u = p_camera.fx * p_centre_camera.x / z + p_camera.cx, v = p_camera.fy * p_centre_camera.y / z + p_camera.cy;
	// Distortion moves pixels by a fraction of the image at most: a quarter image of slack.
	const double slack_x = 0.25 * p_camera.width, slack_y = 0.25 * p_camera.height;
	return u > -margin_x - slack_x && u < p_camera.width + margin_x + slack_x && v > -margin_y - slack_y && v < p_camera.height + margin_y + slack_y;
}

// Bilinear in radiance (each tap through the lut); false when a tap is clipped (255).
bool sample_rgb(const cv::Mat &p_rgb, const glm::dvec2 &p_pixel, const ResponseCurve *p_lut, cv::Vec3f *r_value) {
	const int x0 = int(std::floor(p_pixel.x)), y0 = int(std::floor(p_pixel.y));
	const float ax = float(p_pixel.x - x0), ay = float(p_pixel.y - y0);
	cv::Vec3f sum(0.0f, 0.0f, 0.0f);
	for (int k = 0; k < 4; k++) {
		const int x = x0 + (k & 1), y = y0 + (k >> 1);
		const cv::Vec3b &tap = p_rgb.at<cv::Vec3b>(y, x);
		const float weight = ((k & 1) ? ax : 1.0f - ax) * ((k >> 1) ? ay : 1.0f - ay);
		for (int c = 0; c < 3; c++) {
			if (tap[c] == 255) {
				return false;
			}
			sum[c] += weight * (p_lut ? (*p_lut)[tap[c]] : float(tap[c]) / 255.0f);
		}
	}
	*r_value = sum;
	return true;
}

} // namespace

RgbTextureStats update_coarse_texture_from_rgb(const TexelGeometry &p_geometry, const PinholeParams &p_camera, const Pose &p_world_from_rgb,
		const cv::Mat &p_rgb, const cv::Mat &p_depth_m, const ResponseCurve *p_lut, CoarseTexture *io_texture, const RgbTextureOptions &p_options,
		cv::Mat *r_updated, LightingPairs *r_pairs) {
	RgbTextureStats stats;
	CoarseTexture &tex = *io_texture;
	const int w = p_geometry.width, h = p_geometry.height;
	if (p_rgb.type() != CV_8UC3 || p_depth_m.type() != CV_32FC1 || p_rgb.cols != p_camera.width || p_rgb.rows != p_camera.height ||
			p_depth_m.size() != p_rgb.size() || tex.color.cols != w || tex.color.rows != h || w == 0 ||
			(r_updated && (r_updated->type() != CV_8UC1 || r_updated->size() != tex.color.size()))) {
		return stats;
	}
	if (tex.rgb_quality.size() != tex.color.size()) {
		tex.rgb_quality = cv::Mat(h, w, CV_32FC1, cv::Scalar(0.0));
	}
	const Pose camera_from_world = inverse(p_world_from_rgb);
	const glm::dvec3 camera_position = p_world_from_rgb.translation;
	std::vector<uint8_t> tile_visible(p_geometry.tile_centres.size(), 0);
	for (size_t t = 0; t < tile_visible.size(); t++) {
		tile_visible[t] = tile_in_view(transform_point(camera_from_world, p_geometry.tile_centres[t]), p_geometry.tile_radii[t], p_camera) ? 1 : 0;
	}
	const int pair_step = r_pairs ? r_pairs->begin(h) : 1;
	std::atomic<size_t> visible{ 0 }, updated{ 0 };
	const double max_x = p_camera.width - 1.0 - p_options.border_px, max_y = p_camera.height - 1.0 - p_options.border_px;
	tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int> &p_rows) {
		size_t row_visible = 0, row_updated = 0;
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			cv::Vec3f *color = tex.color.ptr<cv::Vec3f>(y);
			const float *fisheye_quality = tex.quality.ptr<float>(y);
			float *rgb_quality = tex.rgb_quality.ptr<float>(y);
			uint8_t *observed = tex.observed.ptr<uint8_t>(y);
			uint8_t *fresh = r_updated ? r_updated->ptr<uint8_t>(y) : nullptr;
			std::vector<LightingSample> *pairs_row = r_pairs && y % pair_step == 0 ? &r_pairs->rows[size_t(y / pair_step)] : nullptr;
			for (int x = 0; x < w; ++x) {
				const size_t i = size_t(y) * w + x;
				if (!tile_visible[size_t(y / TexelGeometry::tile_size) * p_geometry.tiles_x + x / TexelGeometry::tile_size]) {
					x += TexelGeometry::tile_size - 1 - x % TexelGeometry::tile_size;
					continue;
				}
				if (p_geometry.charts[i] < 0 || fisheye_quality[x] > 0.0f) {
					continue; // not on the surface, or the fisheye's
				}
				const glm::dvec3 point = transform_point(camera_from_world, p_geometry.points[i]);
				glm::dvec2 pixel;
				if (!(point.z > 0.05) || !project_pinhole(p_camera, point, &pixel) || !(pixel.x >= p_options.border_px && pixel.x <= max_x &&
																							 pixel.y >= p_options.border_px && pixel.y <= max_y)) {
					continue;
				}
				const float measured = p_depth_m.at<float>(int(std::lround(pixel.y)), int(std::lround(pixel.x)));
				if (!std::isfinite(measured) || std::abs(double(measured) - point.z) > std::max(p_options.depth_tolerance_m, p_options.depth_tolerance_fraction * point.z)) {
					continue; // something else is in front of it, or the camera cannot tell
				}
				const glm::dvec3 to_camera = camera_position - p_geometry.points[i];
				const double distance = glm::length(to_camera);
				const double cos_view = glm::dot(p_geometry.normals[i], to_camera) / distance;
				if (!(cos_view >= p_options.min_cos_view)) {
					continue;
				}
				++row_visible;
				const double d = std::max(distance, p_options.min_distance_m);
				const float quality = float(cos_view / (d * d));
				const bool replace = quality >= rgb_quality[x] * float(1.0 - p_options.replace_epsilon);
				const bool pair = pairs_row != nullptr && x % pair_step == 0 && rgb_quality[x] > 0.0f;
				cv::Vec3f value;
				if (!(replace || pair) || !sample_rgb(p_rgb, pixel, p_lut, &value)) {
					continue;
				}
				if (pair) {
					const glm::dvec3 &at = p_geometry.points[i];
					pairs_row->push_back(LightingSample{ color[x], value, cv::Vec3f(float(at.x), float(at.y), float(at.z)) });
				}
				if (!replace) {
					continue;
				}
				color[x] = value;
				observed[x] = 255;
				rgb_quality[x] = std::max(rgb_quality[x], quality);
				if (fresh) {
					fresh[x] = 255;
				}
				++row_updated;
			}
		}
		visible += row_visible;
		updated += row_updated;
	});
	stats.texels_visible = visible;
	stats.texels_updated = updated;
	return stats;
}

} // namespace roomprobe
