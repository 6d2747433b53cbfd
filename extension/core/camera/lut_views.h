#pragma once
// Look-up tables that resample a fisheye image into a perspective or an equirectangular view, for
// display and debugging ONLY: the pipeline never undistorts whole frames, it projects texels
// through the model (paper §4.3).

#include "camera_params.h"

#include <io/opencv.h>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <functional>

namespace roomprobe {

// Maps of a view for cv::remap: the source pixel of each view pixel.
struct LutView {
	cv::Mat map_x; // CV_32FC1, source column; -1 where the view sees no valid source pixel
	cv::Mat map_y; // CV_32FC1, source row; -1 likewise
	cv::Mat mask; // CV_8UC1, 255 where valid, 0 where not
};

// Projects a ray of the source camera's frame to a source pixel; false where it is not seen
// (outside the image circle included).
using ProjectToSource = std::function<bool(const glm::dvec3 &p_ray, glm::dvec2 *r_pixel)>;

// View frames are OpenCV's (x right, y down, z forward); p_camera_from_view rotates view
// directions into the source camera's frame (identity: looking along its optical axis).

// An undistorted pinhole view, p_fov_deg wide horizontally, square pixels, centred.
LutView build_perspective_lut(const ProjectToSource &p_project, int p_width, int p_height, double p_fov_deg,
		const glm::dmat3 &p_camera_from_view = glm::dmat3(1.0));
// An equirectangular view of the whole sphere: columns run over longitude -180..180 degrees about
// the view's y axis (0 at the view's +z, +90 at +x), rows over latitude 90 (the view's -y, up) to
// -90 degrees.
LutView build_equirect_lut(const ProjectToSource &p_project, int p_width, int p_height,
		const glm::dmat3 &p_camera_from_view = glm::dmat3(1.0));

// The same for a fisheye under the unified model; valid means inside the image and the circle.
LutView build_perspective_lut(const OmniParams &p_params, int p_width, int p_height, double p_fov_deg,
		const glm::dmat3 &p_camera_from_view = glm::dmat3(1.0));
LutView build_equirect_lut(const OmniParams &p_params, int p_width, int p_height,
		const glm::dmat3 &p_camera_from_view = glm::dmat3(1.0));

// The view direction of an equirectangular pixel (unit, view frame), as build_equirect_lut uses.
glm::dvec3 equirect_direction(int p_width, int p_height, const glm::dvec2 &p_pixel);

// cv::remap with bilinear filtering; pixels outside the mask are black.
cv::Mat apply_lut(const cv::Mat &p_image, const LutView &p_view);

} // namespace roomprobe
