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

// The distortion-free pinhole, in single precision, for per-pixel and per-voxel kernels (dense
// SLAM): images that reach them are undistorted first (has_pinhole_distortion), so the hot loops
// need no Newton iterations. Same pixel convention as above.
struct PinholeIntrinsics {
	float fx = 0.0f, fy = 0.0f; // pixels
	float cx = 0.0f, cy = 0.0f; // pixels
	int width = 0, height = 0; // pixels

	// A camera of the same field of view at 1 / 2^p_level of the size (image pyramids).
	PinholeIntrinsics level(int p_level) const {
		const float s = 1.0f / float(1 << p_level);
		// Pixel centres: (0, 0) is the centre of the top-left pixel at every level.
		return { fx * s, fy * s, (cx + 0.5f) * s - 0.5f, (cy + 0.5f) * s - 0.5f, width >> p_level, height >> p_level };
	}
	// False behind the camera (z <= 0, or NaN); the pixel may lie outside the image.
	bool project(const glm::vec3 &p_point, glm::vec2 *r_pixel) const {
		if (!(p_point.z > 0.0f)) {
			return false;
		}
		*r_pixel = { fx * p_point.x / p_point.z + cx, fy * p_point.y / p_point.z + cy };
		return true;
	}
	// The point at depth p_z (metres along the optical axis) seen at p_pixel.
	glm::vec3 unproject(const glm::vec2 &p_pixel, float p_z) const {
		return { (p_pixel.x - cx) / fx * p_z, (p_pixel.y - cy) / fy * p_z, p_z };
	}
};

PinholeIntrinsics pinhole_intrinsics(const PinholeParams &p_params);
// Whether any distortion coefficient is non-zero.
bool has_pinhole_distortion(const PinholeParams &p_params);

// The vertical field of view in degrees, 2 atan(height / 2 / fy) (a Camera3D's fov with its
// default keep_aspect, KEEP_HEIGHT); 0 for unknown intrinsics.
double pinhole_vertical_fov_degrees(const PinholeParams &p_params);

} // namespace roomprobe
