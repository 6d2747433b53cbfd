#pragma once
// Per-pixel kernels of depth preprocessing and ICP tracking (paper §4.2): plain inline functions
// on raw pointers and glm, no threading, no OpenCV types, so that a GPU path can call the same
// code (InfiniTAM style). The CPU loops that run them are in depth_pyramid.cpp and
// icp_tracker.cpp. Images are row-major with a stride in elements; invalid = NaN.

#include <camera/pinhole_camera.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <cstddef>
#include <limits>

namespace roomprobe {

inline constexpr float ICP_NAN = std::numeric_limits<float>::quiet_NaN();

// ---------------------------------------------------------------- preprocessing

// One pixel of the half-size depth image: the mean of the valid depths (metres) of the 2x2 block
// at (2 p_x, 2 p_y) that lie within p_band_m of the block's nearest depth, so that a block on a
// depth edge is not averaged across it. NaN when the block has no valid depth.
inline float downsample_depth_pixel(const float *p_depth, size_t p_stride, int p_width, int p_height, int p_x, int p_y, float p_band_m) {
	float values[4];
	int count = 0;
	float nearest = std::numeric_limits<float>::infinity();
	for (int dy = 0; dy < 2; ++dy) {
		const int y = 2 * p_y + dy;
		for (int dx = 0; dx < 2; ++dx) {
			const int x = 2 * p_x + dx;
			if (x >= p_width || y >= p_height) {
				continue;
			}
			const float d = p_depth[size_t(y) * p_stride + size_t(x)];
			if (d > 0.0f) { // false for NaN
				values[count++] = d;
				nearest = d < nearest ? d : nearest;
			}
		}
	}
	if (count == 0) {
		return ICP_NAN;
	}
	float sum = 0.0f;
	int used = 0;
	for (int i = 0; i < count; ++i) {
		if (values[i] - nearest <= p_band_m) {
			sum += values[i];
			++used;
		}
	}
	return sum / float(used);
}

// One pixel of an edge-preserving smoothing of a depth image (metres, NaN = none): the mean of
// the valid depths in the (2 p_radius + 1)^2 window within p_band_m of the centre's, weighted by
// p_weights (the window's spatial weights, row by row). Holes stay holes (NaN centre: NaN).
inline float smooth_depth_pixel(const float *p_depth, size_t p_stride, int p_width, int p_height, int p_x, int p_y, int p_radius,
		float p_band_m, const float *p_weights) {
	const float centre = p_depth[size_t(p_y) * p_stride + size_t(p_x)];
	if (!(centre > 0.0f)) {
		return ICP_NAN;
	}
	float sum = 0.0f, weight_sum = 0.0f;
	const int side = 2 * p_radius + 1;
	for (int dy = -p_radius; dy <= p_radius; ++dy) {
		const int y = p_y + dy;
		if (y < 0 || y >= p_height) {
			continue;
		}
		const float *row = p_depth + size_t(y) * p_stride;
		const float *weights = p_weights + size_t((dy + p_radius) * side + p_radius);
		for (int dx = -p_radius; dx <= p_radius; ++dx) {
			const int x = p_x + dx;
			if (x < 0 || x >= p_width) {
				continue;
			}
			const float d = row[x];
			if (std::abs(d - centre) <= p_band_m) { // false for NaN
				sum += weights[dx] * d;
				weight_sum += weights[dx];
			}
		}
	}
	return sum / weight_sum;
}

// The unit normal at (p_x, p_y) of a camera-frame vertex map (xyz interleaved, NaN = none), from
// central differences, turned towards the camera. NaN at the border, next to a hole, or where a
// neighbour's depth differs from the centre's by more than p_max_jump_relative * z (a depth edge,
// where the difference spans two surfaces).
inline glm::vec3 normal_pixel(const float *p_vertices, size_t p_stride, int p_width, int p_height, int p_x, int p_y, float p_max_jump_relative) {
	const glm::vec3 none(ICP_NAN);
	if (p_x < 1 || p_y < 1 || p_x >= p_width - 1 || p_y >= p_height - 1) {
		return none;
	}
	auto at = [&](int x, int y) {
		const float *v = p_vertices + size_t(y) * p_stride + size_t(x) * 3;
		return glm::vec3(v[0], v[1], v[2]);
	};
	const glm::vec3 c = at(p_x, p_y), l = at(p_x - 1, p_y), r = at(p_x + 1, p_y), u = at(p_x, p_y - 1), d = at(p_x, p_y + 1);
	if (!(c.z > 0.0f && l.z > 0.0f && r.z > 0.0f && u.z > 0.0f && d.z > 0.0f)) {
		return none;
	}
	const float jump = p_max_jump_relative * c.z;
	if (std::abs(l.z - c.z) > jump || std::abs(r.z - c.z) > jump || std::abs(u.z - c.z) > jump || std::abs(d.z - c.z) > jump) {
		return none;
	}
	glm::vec3 n = glm::cross(r - l, d - u);
	const float length = glm::length(n);
	if (!(length > 0.0f)) {
		return none;
	}
	n /= length;
	return glm::dot(n, c) > 0.0f ? -n : n;
}

// ---------------------------------------------------------------- ICP data association

// The reference (ModelMaps) as the kernel reads it: world points and normals (xyz interleaved,
// NaN = none) and, for the colour term only, intensity in [0, 1] and its gradient in intensity
// per pixel (NaN = none).
struct IcpModelView {
	const float *points = nullptr;
	const float *normals = nullptr;
	size_t stride = 0; // floats per row of points and normals
	const float *intensity = nullptr; // null: no colour term
	const float *gradient_x = nullptr;
	const float *gradient_y = nullptr;
	size_t intensity_stride = 0; // floats per row of the three above
	PinholeIntrinsics camera; // the model's camera
	glm::mat3 camera_from_world_rotation = glm::mat3(1.0f); // the model's camera pose, inverted
	glm::vec3 camera_from_world_translation = glm::vec3(0.0f); // metres
};

// What one correspondence needs to know of the current estimate and the thresholds.
struct IcpKernelParams {
	glm::mat3 rotation = glm::mat3(1.0f); // world_from_camera's rotation, the current estimate
	glm::vec3 translation = glm::vec3(0.0f); // world_from_camera's translation, metres
	float max_distance_m = 0.1f; // point-to-point distance beyond which a pair is an outlier
	float min_normal_cos = 0.8f; // cos of the largest angle between the two normals
	float colour_weight = 0.0f; // metres per unit intensity; 0: no colour row
	float max_colour_difference = 0.1f; // intensity difference beyond which the colour row is dropped
	// Noise weighting (slam_types.h DepthNoiseModel): a row at depth z is scaled by
	// min(1, noise_reference_sigma_m / (noise_a_m + noise_b_per_m2 (z - noise_c_m)^2)).
	float noise_a_m = 0.0012f, noise_b_per_m2 = 0.0f, noise_c_m = 0.4f;
	float noise_reference_sigma_m = 0.0012f;
};

// The weight of a reading at camera depth p_z_m (see IcpKernelParams): 1 when nearer than the
// reference depth, falling as 1 / sigma(z) beyond.
inline float depth_noise_weight(const IcpKernelParams &p_params, float p_z_m) {
	const float d = p_z_m - p_params.noise_c_m;
	const float sigma = p_params.noise_a_m + p_params.noise_b_per_m2 * d * d;
	return sigma > p_params.noise_reference_sigma_m ? p_params.noise_reference_sigma_m / sigma : 1.0f;
}

// One row of the least-squares system: residual + jacobian . xi, with xi = (omega, delta_t) the
// update of the pose, a rotation omega (radians, world axes) about the camera centre and a
// translation delta_t (metres, world axes): x' = exp(omega) (x - c) + c + delta_t.
struct IcpRow {
	float jacobian[6];
	float residual;
};

// Bilinear sample of a single-channel float image at a sub-pixel position (pixel centres at
// integers); NaN outside or where any of the four neighbours is NaN.
inline float sample_bilinear(const float *p_image, size_t p_stride, int p_width, int p_height, const glm::vec2 &p_pixel) {
	const int x0 = int(std::floor(p_pixel.x)), y0 = int(std::floor(p_pixel.y));
	if (x0 < 0 || y0 < 0 || x0 + 1 >= p_width || y0 + 1 >= p_height) {
		return ICP_NAN;
	}
	const float ax = p_pixel.x - float(x0), ay = p_pixel.y - float(y0);
	const float *row0 = p_image + size_t(y0) * p_stride + size_t(x0);
	const float *row1 = row0 + p_stride;
	return (1.0f - ay) * ((1.0f - ax) * row0[0] + ax * row0[1]) + ay * ((1.0f - ax) * row1[0] + ax * row1[1]);
}

// The correspondence of one current pixel by projective data association: its camera-frame
// vertex p_vertex and normal p_normal are moved to the world by the estimate, projected into the
// model's camera, and paired with the model point and normal at the nearest pixel. Returns the
// number of rows written to r_rows: 0 (no inlier pair), 1 (point-to-plane, r_rows[0]) or 2 (and
// the photometric row r_rows[1], when the model has intensity and the weight is not 0).
// r_squared_distance gets the squared point-to-plane residual of an inlier (metres^2, unweighted
// by the noise weight its rows carry).
// Always inlined: called per pixel, and GCC's size heuristics would otherwise keep it a call
// with its vectors passed through memory.
[[gnu::always_inline]] inline int icp_correspondence(const glm::vec3 &p_vertex, const glm::vec3 &p_normal, float p_intensity, const IcpKernelParams &p_params,
		const IcpModelView &p_model, IcpRow *r_rows, float *r_squared_distance) {
	if (!(p_vertex.z > 0.0f) || std::isnan(p_normal.x)) {
		return 0;
	}
	const glm::vec3 offset = p_params.rotation * p_vertex; // from the camera centre, world axes
	const glm::vec3 point = offset + p_params.translation;
	const glm::vec3 normal = p_params.rotation * p_normal;
	const glm::vec3 in_model = p_model.camera_from_world_rotation * point + p_model.camera_from_world_translation;
	glm::vec2 pixel;
	if (!p_model.camera.project(in_model, &pixel)) {
		return 0;
	}
	// The nearest pixel, rounding halves up; lroundf is a libm call here (no SSE4.1 at build time),
	// and a pixel left of or above -0.5 is outside anyway, so the truncation of the shifted value
	// never meets a negative.
	const float shifted_x = pixel.x + 0.5f, shifted_y = pixel.y + 0.5f;
	if (!(shifted_x > 0.0f && shifted_y > 0.0f && shifted_x < float(p_model.camera.width) && shifted_y < float(p_model.camera.height))) {
		return 0;
	}
	const int u = int(shifted_x), v = int(shifted_y);
	const float *m = p_model.points + size_t(v) * p_model.stride + size_t(u) * 3;
	const float *mn = p_model.normals + size_t(v) * p_model.stride + size_t(u) * 3;
	const glm::vec3 model_point(m[0], m[1], m[2]), model_normal(mn[0], mn[1], mn[2]);
	if (std::isnan(model_point.x) || std::isnan(model_normal.x)) {
		return 0;
	}
	const glm::vec3 difference = point - model_point;
	if (glm::dot(difference, difference) > p_params.max_distance_m * p_params.max_distance_m) {
		return 0;
	}
	if (glm::dot(normal, model_normal) < p_params.min_normal_cos) {
		return 0;
	}
	// Point-to-plane: r = n . (p - m); d r / d omega = offset x n, d r / d delta_t = n. Both
	// scaled by the reading's noise weight.
	const float weight = depth_noise_weight(p_params, p_vertex.z);
	const float residual = glm::dot(model_normal, difference);
	const glm::vec3 moment = glm::cross(offset, model_normal) * weight;
	const glm::vec3 weighted_normal = model_normal * weight;
	IcpRow &row = r_rows[0];
	row.jacobian[0] = moment.x;
	row.jacobian[1] = moment.y;
	row.jacobian[2] = moment.z;
	row.jacobian[3] = weighted_normal.x;
	row.jacobian[4] = weighted_normal.y;
	row.jacobian[5] = weighted_normal.z;
	row.residual = residual * weight;
	*r_squared_distance = residual * residual;
	if (p_model.intensity == nullptr || p_params.colour_weight == 0.0f || std::isnan(p_intensity)) {
		return 1;
	}
	// Photometric: r = w (I_model(pi(q)) - I_current), q the point in the model's camera.
	const int w = p_model.camera.width, h = p_model.camera.height;
	const float model_intensity = sample_bilinear(p_model.intensity, p_model.intensity_stride, w, h, pixel);
	const float gx = sample_bilinear(p_model.gradient_x, p_model.intensity_stride, w, h, pixel);
	const float gy = sample_bilinear(p_model.gradient_y, p_model.intensity_stride, w, h, pixel);
	if (std::isnan(model_intensity) || std::isnan(gx) || std::isnan(gy)) {
		return 1;
	}
	// Specularities, changing screens, occlusion: a photometric outlier, the geometry still counts.
	if (std::abs(model_intensity - p_intensity) > p_params.max_colour_difference) {
		return 1;
	}
	// d pixel / d q (pinhole), then back to world axes: a = R_model^T (d pi / d q)^T grad I.
	const float inv_z = 1.0f / in_model.z;
	const glm::vec3 dq(p_model.camera.fx * gx * inv_z, p_model.camera.fy * gy * inv_z,
			-(p_model.camera.fx * gx * in_model.x + p_model.camera.fy * gy * in_model.y) * inv_z * inv_z);
	const glm::vec3 a = glm::transpose(p_model.camera_from_world_rotation) * dq * (p_params.colour_weight * weight);
	const glm::vec3 colour_moment = glm::cross(offset, a);
	IcpRow &colour = r_rows[1];
	colour.jacobian[0] = colour_moment.x;
	colour.jacobian[1] = colour_moment.y;
	colour.jacobian[2] = colour_moment.z;
	colour.jacobian[3] = a.x;
	colour.jacobian[4] = a.y;
	colour.jacobian[5] = a.z;
	colour.residual = p_params.colour_weight * weight * (model_intensity - p_intensity);
	return 2;
}

} // namespace roomprobe
