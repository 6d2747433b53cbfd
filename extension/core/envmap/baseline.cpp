#include "baseline.h"

#include <camera/omni_camera.h>

#include <glm/gtc/quaternion.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>

namespace roomprobe {

BaselineEnvmap::BaselineEnvmap(int p_size) {
	map = make_cubemap(p_size > 0 ? p_size : 1);
	for (cv::Mat &face : seen_mask) {
		face = cv::Mat::zeros(map.size, map.size, CV_8UC1);
	}
}

void BaselineEnvmap::clear() {
	for (size_t f = 0; f < 6; f++) {
		map.faces[f].setTo(cv::Scalar::all(0.0));
		seen_mask[f].setTo(cv::Scalar::all(0));
	}
}

double BaselineEnvmap::seen_fraction() const {
	double seen = 0.0;
	for (int v = 0; v < map.size; v++) {
		for (int u = 0; u < map.size; u++) {
			int count = 0;
			for (const cv::Mat &face : seen_mask) {
				count += face.at<uint8_t>(v, u) != 0 ? 1 : 0;
			}
			seen += count * cubemap_texel_solid_angle(u, v, map.size);
		}
	}
	return seen / (4.0 * std::numbers::pi);
}

int BaselineEnvmap::add_frame(const cv::Mat &p_image, const OmniParams &p_params, const Pose &p_world_from_fisheye) {
	if (p_image.empty() || p_image.cols != p_params.width || p_image.rows != p_params.height) {
		return 0;
	}
	cv::Mat image;
	switch (p_image.type()) {
		case CV_8UC1:
			cv::cvtColor(p_image, image, cv::COLOR_GRAY2RGB);
			image.convertTo(image, CV_32FC3, 1.0 / 255.0);
			break;
		case CV_8UC3:
			p_image.convertTo(image, CV_32FC3, 1.0 / 255.0);
			break;
		case CV_32FC3:
			image = p_image;
			break;
		default:
			return 0;
	}
	const glm::dquat fisheye_from_world = glm::conjugate(glm::normalize(p_world_from_fisheye.rotation));
	const int n = map.size;
	std::atomic<int> written{ 0 };
	tbb::parallel_for(tbb::blocked_range<int>(0, 6 * n), [&](const tbb::blocked_range<int> &p_rows) {
		int count = 0;
		for (int row = p_rows.begin(); row != p_rows.end(); row++) {
			const int face = row / n;
			const int v = row % n;
			cv::Vec3f *out = map.faces[size_t(face)].ptr<cv::Vec3f>(v);
			uint8_t *seen = seen_mask[size_t(face)].ptr<uint8_t>(v);
			for (int u = 0; u < n; u++) {
				const glm::dvec3 direction = fisheye_from_world * cubemap_direction(face, u, v, n);
				glm::dvec2 pixel;
				if (!project_omni(p_params, direction, &pixel) || !omni_pixel_valid(p_params, pixel)) {
					continue;
				}
				// Bilinear, texel centres at integer pixel coordinates, clamped to the image.
				const double fx = std::clamp(pixel.x, 0.0, double(image.cols - 1));
				const double fy = std::clamp(pixel.y, 0.0, double(image.rows - 1));
				const int x0 = int(std::floor(fx));
				const int y0 = int(std::floor(fy));
				const int x1 = std::min(x0 + 1, image.cols - 1);
				const int y1 = std::min(y0 + 1, image.rows - 1);
				const float ax = float(fx - x0);
				const float ay = float(fy - y0);
				const cv::Vec3f top = image.at<cv::Vec3f>(y0, x0) * (1.0f - ax) + image.at<cv::Vec3f>(y0, x1) * ax;
				const cv::Vec3f bottom = image.at<cv::Vec3f>(y1, x0) * (1.0f - ax) + image.at<cv::Vec3f>(y1, x1) * ax;
				out[u] = top * (1.0f - ay) + bottom * ay;
				seen[u] = 255;
				count++;
			}
		}
		written += count;
	});
	return written.load();
}

} // namespace roomprobe
