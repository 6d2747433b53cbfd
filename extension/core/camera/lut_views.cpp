#include "lut_views.h"

#include "omni_camera.h"

#include <cmath>
#include <cstdint>
#include <numbers>

namespace roomprobe {

namespace {

template <typename DirectionOf>
LutView build_lut(const ProjectToSource &p_project, int p_width, int p_height, const glm::dmat3 &p_camera_from_view,
		const DirectionOf &p_direction_of) {
	LutView view;
	view.map_x.create(p_height, p_width, CV_32FC1);
	view.map_y.create(p_height, p_width, CV_32FC1);
	view.mask.create(p_height, p_width, CV_8UC1);
	for (int row = 0; row < p_height; row++) {
		float *map_x = view.map_x.ptr<float>(row);
		float *map_y = view.map_y.ptr<float>(row);
		uint8_t *mask = view.mask.ptr<uint8_t>(row);
		for (int column = 0; column < p_width; column++) {
			glm::dvec2 pixel;
			const bool valid = p_project(p_camera_from_view * p_direction_of(glm::dvec2(column, row)), &pixel);
			map_x[column] = valid ? float(pixel.x) : -1.0f;
			map_y[column] = valid ? float(pixel.y) : -1.0f;
			mask[column] = valid ? 255 : 0;
		}
	}
	return view;
}

ProjectToSource omni_source(const OmniParams &p_params) {
	return [p_params](const glm::dvec3 &p_ray, glm::dvec2 *r_pixel) {
		// project_omni checks the circle; the image's bounds are omni_pixel_valid's.
		return project_omni(p_params, p_ray, r_pixel) && omni_pixel_valid(p_params, *r_pixel);
	};
}

} // namespace

LutView build_perspective_lut(const ProjectToSource &p_project, int p_width, int p_height, double p_fov_deg,
		const glm::dmat3 &p_camera_from_view) {
	const double focal = 0.5 * p_width / std::tan(0.5 * p_fov_deg * std::numbers::pi / 180.0);
	const glm::dvec2 centre = { 0.5 * (p_width - 1), 0.5 * (p_height - 1) };
	return build_lut(p_project, p_width, p_height, p_camera_from_view, [&](const glm::dvec2 &p_pixel) {
		return glm::dvec3(p_pixel.x - centre.x, p_pixel.y - centre.y, focal);
	});
}

glm::dvec3 equirect_direction(int p_width, int p_height, const glm::dvec2 &p_pixel) {
	const double longitude = ((p_pixel.x + 0.5) / p_width * 2.0 - 1.0) * std::numbers::pi;
	const double latitude = (0.5 - (p_pixel.y + 0.5) / p_height) * std::numbers::pi;
	return { std::cos(latitude) * std::sin(longitude), -std::sin(latitude), std::cos(latitude) * std::cos(longitude) };
}

LutView build_equirect_lut(const ProjectToSource &p_project, int p_width, int p_height, const glm::dmat3 &p_camera_from_view) {
	return build_lut(p_project, p_width, p_height, p_camera_from_view, [&](const glm::dvec2 &p_pixel) {
		return equirect_direction(p_width, p_height, p_pixel);
	});
}

LutView build_perspective_lut(const OmniParams &p_params, int p_width, int p_height, double p_fov_deg,
		const glm::dmat3 &p_camera_from_view) {
	return build_perspective_lut(omni_source(p_params), p_width, p_height, p_fov_deg, p_camera_from_view);
}

LutView build_equirect_lut(const OmniParams &p_params, int p_width, int p_height, const glm::dmat3 &p_camera_from_view) {
	return build_equirect_lut(omni_source(p_params), p_width, p_height, p_camera_from_view);
}

cv::Mat apply_lut(const cv::Mat &p_image, const LutView &p_view) {
	cv::Mat remapped;
	cv::remap(p_image, remapped, p_view.map_x, p_view.map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
	cv::Mat result = cv::Mat::zeros(remapped.size(), remapped.type());
	remapped.copyTo(result, p_view.mask);
	return result;
}

} // namespace roomprobe
