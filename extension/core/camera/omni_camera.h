#pragma once
// The one place for the unified omnidirectional (fisheye) model's projection and unprojection.

#include "camera_params.h"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace roomprobe {

// Projects a point in the camera frame to a pixel. False when the model cannot see it: beyond
// max_angle_deg, or where the unified model has no projection (z <= -xi * |p| side).
bool project_omni(const OmniParams &p_params, const glm::dvec3 &p_point, glm::dvec2 *r_pixel);
// The unit ray of a pixel. False outside the image circle or where the model has no inverse.
bool unproject_omni(const OmniParams &p_params, const glm::dvec2 &p_pixel, glm::dvec3 *r_ray);
// Whether a pixel lies inside the image and the image circle.
bool omni_pixel_valid(const OmniParams &p_params, const glm::dvec2 &p_pixel);

} // namespace roomprobe
