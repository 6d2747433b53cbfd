#pragma once
// Per-voxel and per-pixel kernels of the voxel-hashed TSDF (tsdf_volume.h), InfiniTAM style:
// plain inline functions on plain data, free of threads and of any device API, called from the
// CPU loops in tsdf_volume_integrate.cpp and tsdf_volume_raycast.cpp (and, later, from a GPU path).
//
// Grid: voxel (i, j, k) (integers) sits at world (i, j, k) * voxel_size. Voxels are stored in
// blocks of 8 x 8 x 8; voxel v lies in block v >> 3 (floor division) at local index v & 7.

#include <camera/pinhole_camera.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace roomprobe {

constexpr int TSDF_BLOCK_SIDE = 8; // voxels along each side of a block
constexpr int TSDF_BLOCK_VOXELS = TSDF_BLOCK_SIDE * TSDF_BLOCK_SIDE * TSDF_BLOCK_SIDE;
// Voxel weights count observations in fixed point: a head-on reading adds this much, a slanted
// one less (tsdf_update_voxel_at).
constexpr int TSDF_WEIGHT_UNIT = 32;

// One voxel: 12 bytes.
struct TsdfVoxel {
	float tsdf = 1.0f; // signed distance / truncation, in [-1, 1]; > 0 in front of the surface
	uint16_t weight = 0; // observations averaged into tsdf, in units of 1 / TSDF_WEIGHT_UNIT (capped); 0 = never observed
	uint16_t color_weight = 0; // observations averaged into the colour (only near the surface)
	uint8_t r = 0, g = 0, b = 0; // running-average colour
	uint8_t pad = 0;
};

// A slot of the block hash table (open addressing, linear probing).
struct TsdfHashEntry {
	glm::ivec3 block = glm::ivec3(0); // integer block coordinates
	int32_t slot = -1; // the block's index in the voxel pool; TSDF_HASH_EMPTY when unused
};
constexpr int32_t TSDF_HASH_EMPTY = -1;
constexpr int32_t TSDF_HASH_PENDING = -2; // reserved during allocation, no voxels yet

inline uint32_t tsdf_block_hash(const glm::ivec3 &p_block) {
	// The spatial hash of Teschner et al. (large primes, xor), as InfiniTAM uses.
	return (uint32_t(p_block.x) * 73856093u) ^ (uint32_t(p_block.y) * 19349669u) ^ (uint32_t(p_block.z) * 83492791u);
}

// Block coordinates packed into 63 bits, 21 each (a block is 8 voxels: far beyond any room), for
// one-word compares and sorting.
inline uint64_t tsdf_block_key(const glm::ivec3 &p_block) {
	return (uint64_t(uint32_t(p_block.x) & 0x1FFFFFu)) | (uint64_t(uint32_t(p_block.y) & 0x1FFFFFu) << 21) | (uint64_t(uint32_t(p_block.z) & 0x1FFFFFu) << 42);
}

inline int tsdf_local_index(const glm::ivec3 &p_local) {
	return p_local.x + TSDF_BLOCK_SIDE * (p_local.y + TSDF_BLOCK_SIDE * p_local.z);
}

// Read-only access to the volume for kernels: the hash table and the voxel pool.
struct TsdfView {
	const TsdfHashEntry *entries = nullptr;
	uint32_t mask = 0; // table size - 1 (a power of two)
	const TsdfVoxel *voxels = nullptr; // slot s holds voxels [s * 512, s * 512 + 512)
	float voxel_size = 0.0f; // metres
	float truncation = 0.0f; // metres
};

// The pool slot of a block, or a negative value when it is not allocated.
inline int32_t tsdf_find_slot(const TsdfView &p_view, const glm::ivec3 &p_block) {
	uint32_t i = tsdf_block_hash(p_block) & p_view.mask;
	for (uint32_t probes = 0; probes <= p_view.mask; probes++) {
		const TsdfHashEntry &e = p_view.entries[i];
		if (e.slot == TSDF_HASH_EMPTY) {
			return TSDF_HASH_EMPTY;
		}
		if (e.block == p_block) {
			return e.slot;
		}
		i = (i + 1) & p_view.mask;
	}
	return TSDF_HASH_EMPTY;
}

// The last block looked up, so that neighbouring reads skip the hash.
struct TsdfBlockCache {
	glm::ivec3 block = glm::ivec3(INT32_MIN);
	int32_t slot = TSDF_HASH_EMPTY;
};

// floor for |p_x| < 2^31 (grid and pixel coordinates; callers range-check pixels first), inline: baseline x86-64 has no SSE4.1
// roundss, so std::floor is a libm call, once per voxel and pixel coordinate otherwise.
inline int tsdf_floor(float p_x) {
	const int i = int(p_x);
	return i - int(p_x < float(i));
}

// The voxel at integer grid coordinates, or nullptr when its block is not allocated.
inline const TsdfVoxel *tsdf_voxel_at(const TsdfView &p_view, const glm::ivec3 &p_voxel, TsdfBlockCache *r_cache) {
	const glm::ivec3 block(p_voxel.x >> 3, p_voxel.y >> 3, p_voxel.z >> 3);
	if (block != r_cache->block) {
		r_cache->block = block;
		r_cache->slot = tsdf_find_slot(p_view, block);
	}
	if (r_cache->slot < 0) {
		return nullptr;
	}
	const glm::ivec3 local(p_voxel.x & 7, p_voxel.y & 7, p_voxel.z & 7);
	return &p_view.voxels[size_t(r_cache->slot) * TSDF_BLOCK_VOXELS + size_t(tsdf_local_index(local))];
}

// The 8 voxels around a point given in voxel units (p_grid = world / voxel_size); false when any
// is unallocated or unobserved. r_frac: the point's position inside that cell, in [0, 1)^3.
inline bool tsdf_cell_corners(const TsdfView &p_view, const glm::vec3 &p_grid, TsdfBlockCache *r_cache, const TsdfVoxel *r_corners[8], glm::vec3 *r_frac) {
	const glm::vec3 base_f(float(tsdf_floor(p_grid.x)), float(tsdf_floor(p_grid.y)), float(tsdf_floor(p_grid.z)));
	const glm::ivec3 base(base_f);
	*r_frac = p_grid - base_f;
	const glm::ivec3 local(base.x & 7, base.y & 7, base.z & 7);
	if (local.x < 7 && local.y < 7 && local.z < 7) {
		// The whole cell in one block (most cells): one lookup, fixed offsets.
		const TsdfVoxel *v0 = tsdf_voxel_at(p_view, base, r_cache);
		if (v0 == nullptr) {
			return false;
		}
		for (int c = 0; c < 8; c++) {
			const TsdfVoxel *v = v0 + ((c & 1) + TSDF_BLOCK_SIDE * (((c >> 1) & 1) + TSDF_BLOCK_SIDE * ((c >> 2) & 1)));
			if (v->weight == 0) {
				return false;
			}
			r_corners[c] = v;
		}
		return true;
	}
	for (int c = 0; c < 8; c++) {
		const TsdfVoxel *v = tsdf_voxel_at(p_view, base + glm::ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1), r_cache);
		if (v == nullptr || v->weight == 0) {
			return false;
		}
		r_corners[c] = v;
	}
	return true;
}

// Trilinear tsdf at a point in voxel units; false where any corner is unknown.
inline bool tsdf_trilinear(const TsdfView &p_view, const glm::vec3 &p_grid, TsdfBlockCache *r_cache, float *r_tsdf) {
	const TsdfVoxel *c[8];
	glm::vec3 f;
	if (!tsdf_cell_corners(p_view, p_grid, r_cache, c, &f)) {
		return false;
	}
	const float x00 = c[0]->tsdf + (c[1]->tsdf - c[0]->tsdf) * f.x;
	const float x10 = c[2]->tsdf + (c[3]->tsdf - c[2]->tsdf) * f.x;
	const float x01 = c[4]->tsdf + (c[5]->tsdf - c[4]->tsdf) * f.x;
	const float x11 = c[6]->tsdf + (c[7]->tsdf - c[6]->tsdf) * f.x;
	const float y0 = x00 + (x10 - x00) * f.y;
	const float y1 = x01 + (x11 - x01) * f.y;
	*r_tsdf = y0 + (y1 - y0) * f.z;
	return true;
}

// Trilinear colour (0..255 per channel) over the corners that have one; false when none has.
inline bool tsdf_trilinear_color(const TsdfView &p_view, const glm::vec3 &p_grid, TsdfBlockCache *r_cache, glm::vec3 *r_rgb) {
	const glm::vec3 base_f(float(tsdf_floor(p_grid.x)), float(tsdf_floor(p_grid.y)), float(tsdf_floor(p_grid.z)));
	const glm::ivec3 base(base_f);
	const glm::vec3 f = p_grid - base_f;
	glm::vec3 sum(0.0f);
	float total = 0.0f;
	for (int c = 0; c < 8; c++) {
		const glm::ivec3 o(c & 1, (c >> 1) & 1, (c >> 2) & 1);
		const TsdfVoxel *v = tsdf_voxel_at(p_view, base + o, r_cache);
		if (v == nullptr || v->color_weight == 0) {
			continue;
		}
		const float w = (o.x ? f.x : 1.0f - f.x) * (o.y ? f.y : 1.0f - f.y) * (o.z ? f.z : 1.0f - f.z);
		sum += w * glm::vec3(v->r, v->g, v->b);
		total += w;
	}
	if (!(total > 1e-6f)) {
		return false;
	}
	*r_rgb = sum / total;
	return true;
}

// What the per-voxel update needs: the frame and the limits (tsdf_volume.h's TsdfOptions).
struct TsdfFrameView {
	PinholeIntrinsics camera;
	glm::mat3 camera_from_world_rotation = glm::mat3(1.0f);
	glm::vec3 camera_from_world_translation = glm::vec3(0.0f);
	const float *depth = nullptr; // CV_32FC1 rows, metres; NaN where no usable reading (clean_depth)
	size_t depth_stride = 0; // floats per row
	const uint8_t *rgb = nullptr; // CV_8UC3 rows, R, G, B
	size_t rgb_stride = 0; // bytes per row
	const float *slope = nullptr; // CV_32FC1 rows (tsdf_depth_slope), NaN where unknown
	size_t slope_stride = 0; // floats per row
	float min_slope = 0.3f; // readings with a smaller slope factor only carve free space
	float truncation_m = 0.04f;
	float color_band_m = 0.01f;
	float min_depth_m = 0.3f;
	float max_depth_m = 4.0f;
	// A voxel further than this behind the reading on its pixel cannot change, whatever the
	// bilinear depth and the slope factor (tsdf_behind_limit).
	float behind_limit_m = 0.1533f;
	uint16_t max_weight = 64;
	uint16_t max_color_weight = 8;
	// Voxels whose update could not change them are rejected from the nearest reading alone,
	// before the bilinear depth (false: every voxel takes the whole computation, the plain path
	// the tests compare with; the result is the same).
	bool early_exits = true;
};

// std::lround for 0 <= p_x < 2^31, inline (libm's lroundf is a call per voxel): the truncation,
// plus one where the exact remainder reaches a half (halves away from zero, as lround).
inline int tsdf_round_positive(float p_x) {
	const int i = int(p_x);
	return i + int(p_x - float(i) >= 0.5f);
}

// How far behind the reading on its pixel a voxel can be and still change: the bilinear depth
// differs from that reading by less than half the band, and eta >= -truncation is needed with a
// slope factor of at least min_slope.
inline float tsdf_behind_limit(float p_truncation_m, float p_min_slope) {
	return p_truncation_m * (0.5f + 1.0f / std::max(p_min_slope, 1e-3f));
}

// std::fmin and std::fmax inline (NaN loses to a number, as there).
inline float tsdf_fmin(float p_a, float p_b) {
	return (p_b < p_a || p_a != p_a) ? p_b : p_a;
}
inline float tsdf_fmax(float p_a, float p_b) {
	return (p_b > p_a || p_a != p_a) ? p_b : p_a;
}

// A usable depth reading (NaN and 0 are none).
inline bool tsdf_depth_valid(float p_depth, float p_min, float p_max) {
	return p_depth >= p_min && p_depth <= p_max; // false for NaN
}

// The slope factor of a depth pixel: -n . (x / z), with n the unit normal of the surface there
// and x the pixel's point; the point-to-plane distance of a point on the pixel's ray is
// (reading - z) times it. n comes from central differences of the neighbouring readings, one-sided
// where a neighbour is missing, off the image or further than p_max_jump_m in depth (an edge);
// NaN where neither side along a row or a column is usable.
inline float tsdf_depth_slope(const float *p_depth, size_t p_stride, const PinholeIntrinsics &p_camera, int p_u, int p_v, float p_max_jump_m) {
	const float nan = std::numeric_limits<float>::quiet_NaN();
	const float d = p_depth[size_t(p_v) * p_stride + size_t(p_u)];
	if (!(d > 0.0f)) {
		return nan;
	}
	const glm::vec2 px = glm::vec2(float(p_u), float(p_v));
	const glm::vec3 x = p_camera.unproject(px, d);
	// The point of neighbour (p_u + du, p_v + dv), or false when it is not usable.
	auto neighbour = [&](int p_du, int p_dv, glm::vec3 *r_point) {
		const int u = p_u + p_du, v = p_v + p_dv;
		if (u < 0 || v < 0 || u >= p_camera.width || v >= p_camera.height) {
			return false;
		}
		const float dn = p_depth[size_t(v) * p_stride + size_t(u)];
		if (!(std::fabs(dn - d) < p_max_jump_m)) { // false for NaN
			return false;
		}
		*r_point = p_camera.unproject(glm::vec2(float(u), float(v)), dn);
		return true;
	};
	// The tangent along one image axis: central where both neighbours are usable.
	auto tangent = [&](int p_du, int p_dv, glm::vec3 *r_tangent) {
		glm::vec3 a, b;
		const bool has_a = neighbour(-p_du, -p_dv, &a), has_b = neighbour(p_du, p_dv, &b);
		if (has_a && has_b) {
			*r_tangent = b - a;
		} else if (has_b) {
			*r_tangent = b - x;
		} else if (has_a) {
			*r_tangent = x - a;
		} else {
			return false;
		}
		return true;
	};
	glm::vec3 tx, ty;
	if (!tangent(1, 0, &tx) || !tangent(0, 1, &ty)) {
		return nan;
	}
	const glm::vec3 n = glm::cross(tx, ty);
	const float len = glm::length(n);
	if (!(len > 0.0f)) {
		return nan;
	}
	return std::fabs(glm::dot(n, x)) / (len * x.z);
}

// Averages pixel (p_u, p_v)'s colour into a voxel near the surface, the weight capped at
// max_color_weight frames.
inline void tsdf_blend_color(const TsdfFrameView &p_frame, int p_u, int p_v, TsdfVoxel *r_voxel) {
	const uint8_t *px = p_frame.rgb + size_t(p_v) * p_frame.rgb_stride + size_t(p_u) * 3;
	const float cw = float(r_voxel->color_weight);
	r_voxel->r = uint8_t(tsdf_round_positive((float(r_voxel->r) * cw + float(px[0])) / (cw + 1.0f)));
	r_voxel->g = uint8_t(tsdf_round_positive((float(r_voxel->g) * cw + float(px[1])) / (cw + 1.0f)));
	r_voxel->b = uint8_t(tsdf_round_positive((float(r_voxel->b) * cw + float(px[2])) / (cw + 1.0f)));
	if (r_voxel->color_weight < p_frame.max_color_weight) {
		r_voxel->color_weight++;
	}
}

// Folds one frame into one voxel: the signed distance to the tangent
// plane of the reading on the voxel's ray (tsdf_depth_slope), truncated to [-1, 1] and skipped
// well behind the surface, averaged with a capped weight; the colour only within color_band of
// the surface, where the pixel really shows this voxel. True when the voxel changed.
// p_camera_point: the voxel's point in the camera's frame (tsdf_volume_integrate.cpp steps through a
// block's voxels there).
inline bool tsdf_update_voxel_at(const TsdfFrameView &p_frame, const glm::vec3 &p_camera_point, TsdfVoxel *r_voxel) {
	const glm::vec3 &pc = p_camera_point;
	glm::vec2 pixel;
	if (!p_frame.camera.project(pc, &pixel)) {
		return false;
	}
	// Depth at the voxel's own ray: bilinear between the 4 pixels around it where they agree
	// (within half the truncation band), else the nearest pixel, so that no depth is blended across
	// an occlusion edge. Rounding to the nearest pixel alone would put each voxel up to half a
	// pixel off its ray: a tsdf error of 0.5 px * depth / f * tan(tilt), which turns normals.
	// The nearest pixel, floor(pixel + 0.5), in the image (the range test first, so that the
	// truncation below is a floor and NaN is out).
	const float us = pixel.x + 0.5f, vs = pixel.y + 0.5f;
	if (!(us >= 0.0f && vs >= 0.0f && us < float(p_frame.camera.width) && vs < float(p_frame.camera.height))) {
		return false;
	}
	const int u = int(us), v = int(vs);
	float depth = p_frame.depth[size_t(v) * p_frame.depth_stride + size_t(u)];
	if (!(depth == depth)) {
		return false; // no reading (NaN: the depth is clean)
	}
	// Most voxels of a block lie well behind the reading: skip them before the bilinear depth
	// and the slope factor (tsdf_behind_limit).
	if (depth - pc.z < -p_frame.behind_limit_m) {
		return false;
	}
	const float slope = p_frame.slope[size_t(v) * p_frame.slope_stride + size_t(u)];
	const bool has_plane = slope >= p_frame.min_slope; // false for NaN
	bool far_free = false;
	if (p_frame.early_exits) {
		// The same with this pixel's own slope factor: the bilinear depth lies within half the
		// band (and a rounding margin) of this reading, so eta lies within [eta_lo, eta_hi].
		const float spread = 0.5f * p_frame.truncation_m + 1e-5f;
		const float factor = has_plane ? slope : 1.0f;
		const float eta_hi = (depth + spread - pc.z) * factor;
		if (eta_hi < -p_frame.truncation_m || (!has_plane && eta_hi < p_frame.truncation_m)) {
			return false;
		}
		// Free space beyond the band whatever the bilinear depth: the tsdf goes to exactly +1 and
		// no colour is taken, so the bilinear depth is not needed; and a voxel already at +1 with
		// the full weight does not change at all.
		const float eta_lo = (depth - spread - pc.z) * factor;
		far_free = eta_lo >= p_frame.truncation_m && eta_lo >= p_frame.color_band_m;
		if (far_free && r_voxel->tsdf == 1.0f && r_voxel->weight == uint16_t(int(p_frame.max_weight) * TSDF_WEIGHT_UNIT)) {
			return false;
		}
	}
	const int u0 = tsdf_floor(pixel.x), v0 = tsdf_floor(pixel.y); // pixel is within half a pixel of the image here
	if (!far_free && u0 >= 0 && v0 >= 0 && u0 + 1 < p_frame.camera.width && v0 + 1 < p_frame.camera.height) {
		const float *r0 = p_frame.depth + size_t(v0) * p_frame.depth_stride + size_t(u0);
		const float *r1 = r0 + p_frame.depth_stride;
		const float d00 = r0[0], d10 = r0[1], d01 = r1[0], d11 = r1[1];
		const float lo = std::min(std::min(d00, d10), std::min(d01, d11));
		const float hi = std::max(std::max(d00, d10), std::max(d01, d11));
		const float sum = d00 + d10 + d01 + d11; // NaN when any has no reading
		if (sum == sum && hi - lo < 0.5f * p_frame.truncation_m) {
			const float fx = pixel.x - float(u0), fy = pixel.y - float(v0);
			depth = (d00 * (1.0f - fx) + d10 * fx) * (1.0f - fy) + (d01 * (1.0f - fx) + d11 * fx) * fy;
		}
	}
	// Point-to-plane distance to the observed surface (tangent plane at the reading): the
	// projective difference times the pixel's slope factor, so that the views that see a surface
	// at different angles agree on the distance field around it (the plain projective difference
	// grows as 1 / cos of the view angle, and fused views would bend the gradient). Readings
	// slanted beyond min_slope, or without a tangent plane (edges), only carve free space.
	const float eta = (depth - pc.z) * (has_plane ? slope : 1.0f);
	if (eta < -p_frame.truncation_m || (!has_plane && eta < p_frame.truncation_m)) {
		return false; // hidden behind the observed surface, or near one seen too poorly
	}
	const float sdf = std::min(1.0f, eta / p_frame.truncation_m);
	// Slanted readings count less (cos^2 of the view angle): their depth is the least certain
	// and the tangent plane the poorest stand-in for the surface away from the reading.
	const float c = has_plane ? std::min(1.0f, slope) : 0.0f;
	const int add = std::max(1, tsdf_round_positive(c * c * float(TSDF_WEIGHT_UNIT)));
	const float w = float(r_voxel->weight);
	r_voxel->tsdf = (r_voxel->tsdf * w + sdf * float(add)) / (w + float(add));
	r_voxel->weight = uint16_t(std::min(int(r_voxel->weight) + add, int(p_frame.max_weight) * TSDF_WEIGHT_UNIT));
	if (std::fabs(eta) < p_frame.color_band_m) {
		tsdf_blend_color(p_frame, u, v, r_voxel);
	}
	return true;
}

// The ray parameter where a ray leaves an axis-aligned box it is inside (or on).
inline float tsdf_box_exit(const glm::vec3 &p_origin, const glm::vec3 &p_inv_dir, const glm::vec3 &p_box_min, const glm::vec3 &p_box_max) {
	const glm::vec3 t0 = (p_box_min - p_origin) * p_inv_dir;
	const glm::vec3 t1 = (p_box_max - p_origin) * p_inv_dir;
	const glm::vec3 tfar = glm::max(t0, t1);
	return tsdf_fmin(tfar.x, tsdf_fmin(tfar.y, tfar.z));
}

// Clips [r_t0, r_t1] to the part of the ray inside a box; false when none is.
inline bool tsdf_clip_to_box(const glm::vec3 &p_origin, const glm::vec3 &p_inv_dir, const glm::vec3 &p_box_min, const glm::vec3 &p_box_max, float *r_t0, float *r_t1) {
	const glm::vec3 t0 = (p_box_min - p_origin) * p_inv_dir;
	const glm::vec3 t1 = (p_box_max - p_origin) * p_inv_dir;
	const glm::vec3 tnear = glm::min(t0, t1);
	const glm::vec3 tfar = glm::max(t0, t1);
	*r_t0 = tsdf_fmax(*r_t0, tsdf_fmax(tnear.x, tsdf_fmax(tnear.y, tnear.z)));
	*r_t1 = tsdf_fmin(*r_t1, tsdf_fmin(tfar.x, tsdf_fmin(tfar.y, tfar.z)));
	return *r_t0 <= *r_t1;
}

// The tsdf gradient at a point in voxel units, by central differences one voxel apart, falling
// back to the gradient of the trilinear cell the point is in near unobserved voxels.
inline bool tsdf_gradient(const TsdfView &p_view, const glm::vec3 &p_grid, TsdfBlockCache *r_cache, glm::vec3 *r_gradient) {
	float fp[3], fm[3];
	bool ok = true;
	for (int a = 0; a < 3 && ok; a++) {
		glm::vec3 d(0.0f);
		d[a] = 1.0f;
		ok = tsdf_trilinear(p_view, p_grid + d, r_cache, &fp[a]) && tsdf_trilinear(p_view, p_grid - d, r_cache, &fm[a]);
	}
	if (ok) {
		*r_gradient = glm::vec3(fp[0] - fm[0], fp[1] - fm[1], fp[2] - fm[2]);
		return true;
	}
	const TsdfVoxel *c[8];
	glm::vec3 f;
	if (!tsdf_cell_corners(p_view, p_grid, r_cache, c, &f)) {
		return false;
	}
	glm::vec3 g(0.0f);
	for (int i = 0; i < 8; i++) {
		const glm::ivec3 o(i & 1, (i >> 1) & 1, (i >> 2) & 1);
		const float wx = o.x ? f.x : 1.0f - f.x, wy = o.y ? f.y : 1.0f - f.y, wz = o.z ? f.z : 1.0f - f.z;
		const float s = c[i]->tsdf;
		g.x += s * (o.x ? 1.0f : -1.0f) * wy * wz;
		g.y += s * (o.y ? 1.0f : -1.0f) * wx * wz;
		g.z += s * (o.z ? 1.0f : -1.0f) * wx * wy;
	}
	*r_gradient = g;
	return true;
}

// What the raycast of one pixel gives.
struct TsdfRayHit {
	glm::vec3 point = glm::vec3(0.0f); // world metres
	glm::vec3 normal = glm::vec3(0.0f); // world, unit, towards the camera
	glm::vec3 rgb = glm::vec3(0.0f); // 0..255
	float depth = 0.0f; // metres along the optical axis
};

// Limits of one pixel's march (tsdf_volume_raycast.cpp fills them from TsdfOptions and the bounds of
// the allocated blocks).
struct TsdfRayParams {
	glm::vec3 origin = glm::vec3(0.0f); // the camera centre, world metres
	glm::mat3 world_from_camera_rotation = glm::mat3(1.0f);
	float min_depth_m = 0.3f, max_depth_m = 4.0f; // along the optical axis
	glm::vec3 bounds_min = glm::vec3(0.0f), bounds_max = glm::vec3(0.0f); // allocated blocks, world
	// The normal costs six trilinear reads a hit; a cubemap's dense pass needs none.
	bool normals = true;
};

// Finds the surface along the ray parameter range [p_t0, p_t1] by refining a bracket
// (p_ta, tsdf > 0) .. (p_tb, tsdf <= 0) with regula falsi on the trilinear tsdf.
inline float tsdf_refine_crossing(const TsdfView &p_view, const glm::vec3 &p_origin_grid, const glm::vec3 &p_dir_grid, float p_ta, float p_fa, float p_tb, float p_fb, TsdfBlockCache *r_cache) {
	for (int i = 0; i < 3; i++) {
		const float t = p_ta + (p_tb - p_ta) * p_fa / (p_fa - p_fb);
		float f;
		if (!tsdf_trilinear(p_view, p_origin_grid + t * p_dir_grid, r_cache, &f)) {
			return t;
		}
		if (f > 0.0f) {
			p_ta = t;
			p_fa = f;
		} else {
			p_tb = t;
			p_fb = f;
		}
	}
	return p_ta + (p_tb - p_ta) * p_fa / (p_fa - p_fb);
}

// One pixel's march as state that can be resumed a sample at a time, so that a thread can
// interleave several rays (tsdf_volume_raycast.cpp): the march waits on the voxel pool's memory
// more than it computes, and independent rays overlap those waits.
struct TsdfRayMarch {
	glm::vec3 dir_camera = glm::vec3(0.0f), dir = glm::vec3(0.0f); // unit, camera and world
	glm::vec3 origin_grid = glm::vec3(0.0f), dir_grid = glm::vec3(0.0f), inv_dir = glm::vec3(0.0f);
	float t = 0.0f, t_end = 0.0f; // metres along the ray
	bool have_prev = false;
	float t_prev = 0.0f, f_prev = 0.0f;
	TsdfBlockCache cache;
	int steps = 0; // samples taken (for the tests of skipping)
};

enum class TsdfRayStatus { Marching, Hit, Miss };

// Sets up one pixel's march; false when its ray misses the allocated blocks' bounds.
inline bool tsdf_ray_begin(const TsdfRayParams &p_ray, const PinholeIntrinsics &p_camera, float p_voxel_size, int p_u, int p_v, TsdfRayMarch *r_march) {
	TsdfRayMarch &m = *r_march;
	m = TsdfRayMarch();
	m.dir_camera = glm::normalize(p_camera.unproject(glm::vec2(float(p_u), float(p_v)), 1.0f));
	m.dir = p_ray.world_from_camera_rotation * m.dir_camera; // unit
	const float inv_vs = 1.0f / p_voxel_size;
	// Work in voxel units along the ray: t is metres, the grid point is (origin + t dir) / vs.
	m.origin_grid = p_ray.origin * inv_vs;
	m.dir_grid = m.dir * inv_vs;
	m.inv_dir = glm::vec3(1.0f / m.dir.x, 1.0f / m.dir.y, 1.0f / m.dir.z);
	m.t = p_ray.min_depth_m / m.dir_camera.z;
	m.t_end = p_ray.max_depth_m / m.dir_camera.z;
	return tsdf_clip_to_box(p_ray.origin, m.inv_dir, p_ray.bounds_min, p_ray.bounds_max, &m.t, &m.t_end);
}

// The surface where the march bracketed it, between (t_prev, f_prev) and (p_t, p_f).
inline bool tsdf_ray_hit(const TsdfView &p_view, const TsdfRayParams &p_ray, TsdfRayMarch *io_march, float p_t, float p_f, TsdfRayHit *r_hit) {
	TsdfRayMarch &m = *io_march;
	const float ts = tsdf_refine_crossing(p_view, m.origin_grid, m.dir_grid, m.t_prev, m.f_prev, p_t, p_f, &m.cache);
	const glm::vec3 gs = m.origin_grid + ts * m.dir_grid;
	if (p_ray.normals) {
		glm::vec3 gradient;
		if (!tsdf_gradient(p_view, gs, &m.cache, &gradient) || !(glm::dot(gradient, gradient) > 0.0f)) {
			return false;
		}
		glm::vec3 n = glm::normalize(gradient);
		if (glm::dot(n, m.dir) > 0.0f) {
			n = -n;
		}
		r_hit->normal = n;
	} else {
		r_hit->normal = glm::vec3(std::numeric_limits<float>::quiet_NaN());
	}
	r_hit->point = p_ray.origin + ts * m.dir;
	r_hit->depth = ts * m.dir_camera.z;
	if (!tsdf_trilinear_color(p_view, gs, &m.cache, &r_hit->rgb)) {
		r_hit->rgb = glm::vec3(0.0f);
	}
	return true;
}

// One sample of the march: a block at a time through unallocated blocks, in steps of a fraction
// of the truncation band while the tsdf is large, and a half voxel near the surface, until the
// tsdf changes sign from + to -.
inline TsdfRayStatus tsdf_ray_step(const TsdfView &p_view, const TsdfRayParams &p_ray, TsdfRayMarch *io_march, TsdfRayHit *r_hit) {
	TsdfRayMarch &m = *io_march;
	if (!(m.t <= m.t_end)) {
		return TsdfRayStatus::Miss;
	}
	const float vs = p_view.voxel_size;
	const float fine_step = 0.5f * vs;
	m.steps++;
	const glm::vec3 g = m.origin_grid + m.t * m.dir_grid;
	// The nearest voxel decides: its block is looked up once per block the ray enters.
	const glm::ivec3 voxel(tsdf_floor(g.x + 0.5f), tsdf_floor(g.y + 0.5f), tsdf_floor(g.z + 0.5f));
	const TsdfVoxel *nearest = tsdf_voxel_at(p_view, voxel, &m.cache);
	if (m.cache.slot < 0) {
		// Unallocated: nothing was seen here; jump to where the ray leaves the region whose
		// nearest voxels lie in this block, [8 b - 0.5, 8 b + 7.5) voxels.
		const glm::vec3 bmin = (glm::vec3(m.cache.block) * float(TSDF_BLOCK_SIDE) - glm::vec3(0.5f)) * vs;
		m.t = tsdf_fmax(tsdf_box_exit(p_ray.origin, m.inv_dir, bmin, bmin + glm::vec3(vs * float(TSDF_BLOCK_SIDE))), m.t) + 1e-3f * vs;
		m.have_prev = false;
		return TsdfRayStatus::Marching;
	}
	// The nearest voxel while far from the surface (one read); trilinear within two voxels
	// of it, where the crossing is bracketed.
	if (nearest->weight == 0) {
		m.have_prev = false; // unobserved voxels around: creep through them
		m.t += fine_step;
		return TsdfRayStatus::Marching;
	}
	float f = nearest->tsdf;
	if (std::fabs(f) * p_view.truncation < 2.0f * vs) {
		float fine;
		if (tsdf_trilinear(p_view, g, &m.cache, &fine)) {
			f = fine;
		}
	}
	if (m.have_prev && m.f_prev > 0.0f && f <= 0.0f) {
		return tsdf_ray_hit(p_view, p_ray, &m, m.t, f, r_hit) ? TsdfRayStatus::Hit : TsdfRayStatus::Miss;
	}
	m.have_prev = true;
	m.t_prev = m.t;
	m.f_prev = f;
	// Far from the surface the tsdf is about the distance to it (sphere tracing, with a margin
	// for where it over-estimates it: concave corners); near it, half-voxel steps keep the
	// bracket tight.
	m.t += f > 0.0f ? std::max(fine_step, 0.8f * f * p_view.truncation) : fine_step;
	return TsdfRayStatus::Marching;
}

// Asks for the memory the march's next sample reads (its nearest voxel and trilinear cell), so
// that it arrives while other rays step. Looks the block up as that sample would, into its cache
// (the same slot: the table does not change during a raycast), so the march is unchanged.
inline void tsdf_ray_prefetch(const TsdfView &p_view, TsdfRayMarch *io_march) {
	TsdfRayMarch &m = *io_march;
	if (!(m.t <= m.t_end)) {
		return;
	}
	const glm::vec3 g = m.origin_grid + m.t * m.dir_grid;
	const glm::ivec3 voxel(tsdf_floor(g.x + 0.5f), tsdf_floor(g.y + 0.5f), tsdf_floor(g.z + 0.5f));
	// tsdf_voxel_at's lookup written out: through the call, the whole raycast took 8 % longer.
	const glm::ivec3 block(voxel.x >> 3, voxel.y >> 3, voxel.z >> 3);
	if (block != m.cache.block) {
		m.cache.block = block;
		m.cache.slot = tsdf_find_slot(p_view, block);
	}
	if (m.cache.slot >= 0) {
		const TsdfVoxel *base = &p_view.voxels[size_t(m.cache.slot) * TSDF_BLOCK_VOXELS];
		const glm::ivec3 local(voxel.x & 7, voxel.y & 7, voxel.z & 7);
		__builtin_prefetch(base + tsdf_local_index(local));
		// A trilinear cell around the sample reaches the rows above and behind (4 lines), indexed in
		// this block: a hint only, so a cell that starts in the block before asks for rows it will
		// not read.
		const glm::ivec3 cell(tsdf_floor(g.x) & 7, tsdf_floor(g.y) & 7, tsdf_floor(g.z) & 7);
		const int i = tsdf_local_index(cell);
		if (cell.y < 7) {
			__builtin_prefetch(base + i + TSDF_BLOCK_SIDE);
		}
		if (cell.z < 7) {
			__builtin_prefetch(base + i + TSDF_BLOCK_SIDE * TSDF_BLOCK_SIDE);
			if (cell.y < 7) {
				__builtin_prefetch(base + i + TSDF_BLOCK_SIDE * TSDF_BLOCK_SIDE + TSDF_BLOCK_SIDE);
			}
		}
	}
}

// Marches one pixel's ray to its first surface (tsdf_ray_step); r_steps counts the samples.
inline bool tsdf_raycast_pixel(const TsdfView &p_view, const TsdfRayParams &p_ray, const PinholeIntrinsics &p_camera, int p_u, int p_v, TsdfRayHit *r_hit, int *r_steps) {
	TsdfRayMarch march;
	if (!tsdf_ray_begin(p_ray, p_camera, p_view.voxel_size, p_u, p_v, &march)) {
		return false;
	}
	TsdfRayStatus status = TsdfRayStatus::Marching;
	while (status == TsdfRayStatus::Marching) {
		status = tsdf_ray_step(p_view, p_ray, &march, r_hit);
	}
	*r_steps += march.steps;
	return status == TsdfRayStatus::Hit;
}

} // namespace roomprobe
