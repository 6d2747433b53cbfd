#pragma once
// The one place for the pinhole camera's projection and unprojection.

#include "camera_params.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace roomprobe {

// Projects a point in the camera frame to a pixel. False when the point is not in front of the
// camera (z <= 0); the pixel may still lie outside the image.
bool project_pinhole(const PinholeParams &p_params, const glm::dvec3 &p_point, glm::dvec2 *r_pixel);
// The ray through a pixel, undistorted (iteratively, as cv::undistortPoints), as (x, y, 1).
glm::dvec3 unproject_pinhole(const PinholeParams &p_params, const glm::dvec2 &p_pixel);

} // namespace roomprobe
