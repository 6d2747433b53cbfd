#include "slam/tsdf_integrate_simd.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define RP_TSDF_SIMD 1
#endif

#include <cstddef>

namespace roomprobe {

#ifdef RP_TSDF_SIMD

bool tsdf_simd_available() {
	static const bool available = __builtin_cpu_supports("avx2");
	return available;
}

namespace {

#define RP_AVX2 __attribute__((target("avx2")))

// Lanes where p_mask is set, as a bit per lane.
RP_AVX2 inline int lanes(__m256 p_mask) {
	return _mm256_movemask_ps(p_mask);
}

// tsdf_floor per lane (truncation, less one where that rounded up).
RP_AVX2 inline __m256i floor_epi32(__m256 p_x) {
	const __m256i i = _mm256_cvttps_epi32(p_x);
	const __m256 rounded_up = _mm256_cmp_ps(p_x, _mm256_cvtepi32_ps(i), _CMP_LT_OQ);
	return _mm256_add_epi32(i, _mm256_castps_si256(rounded_up)); // + (-1) where set
}

// (p_a < p_b) ? p_a : p_b per lane, as std::min(p_b, p_a) picks for numbers.
RP_AVX2 inline __m256 min_ordered(__m256 p_a, __m256 p_b) {
	return _mm256_blendv_ps(p_b, p_a, _mm256_cmp_ps(p_a, p_b, _CMP_LT_OQ));
}

RP_AVX2 inline __m256 gather(const float *p_base, __m256i p_index, __m256 p_mask) {
	return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), p_base, p_index, p_mask, 4);
}

// tsdf_update_row_simd's steps, split out for reading: always inlined, so that the kernel stays one
// function with no calls.

// tsdf_update_voxel_at's early exits, so that the same voxels count as changed: the live lanes
// left. r_far_free: lanes in free space beyond the band whatever the bilinear depth.
RP_AVX2 __attribute__((always_inline)) static inline __m256 skip_early_exits(const TsdfFrameView &p_frame, __m256 p_live, __m256 p_z, __m256 p_nearest,
		__m256 p_factor, __m256 p_has_plane, __m256 p_old_tsdf, __m256i p_old_weight, int p_full_weight, __m256 *r_far_free) {
	const __m256 one = _mm256_set1_ps(1.0f);
	const __m256 truncation = _mm256_set1_ps(p_frame.truncation_m), neg_truncation = _mm256_set1_ps(-p_frame.truncation_m);
	const __m256 spread = _mm256_set1_ps(0.5f * p_frame.truncation_m + 1e-5f);
	const __m256 eta_hi = _mm256_mul_ps(_mm256_sub_ps(_mm256_add_ps(p_nearest, spread), p_z), p_factor);
	const __m256 hidden = _mm256_or_ps(_mm256_cmp_ps(eta_hi, neg_truncation, _CMP_LT_OQ),
			_mm256_andnot_ps(p_has_plane, _mm256_cmp_ps(eta_hi, truncation, _CMP_LT_OQ)));
	const __m256 saturated = _mm256_and_ps(_mm256_cmp_ps(p_old_tsdf, one, _CMP_EQ_OQ),
			_mm256_castsi256_ps(_mm256_cmpeq_epi32(p_old_weight, _mm256_set1_epi32(p_full_weight))));
	const __m256 eta_lo = _mm256_mul_ps(_mm256_sub_ps(_mm256_sub_ps(p_nearest, spread), p_z), p_factor);
	const __m256 far_free = _mm256_and_ps(_mm256_cmp_ps(eta_lo, truncation, _CMP_GE_OQ), _mm256_cmp_ps(eta_lo, _mm256_set1_ps(p_frame.color_band_m), _CMP_GE_OQ));
	*r_far_free = far_free;
	const __m256 free_again = _mm256_and_ps(saturated, far_free);
	return _mm256_andnot_ps(_mm256_or_ps(hidden, free_again), p_live);
}

// The bilinear depth where the four pixels around agree, else p_nearest.
RP_AVX2 __attribute__((always_inline)) static inline __m256 bilinear_depth(const TsdfFrameView &p_frame, __m256 p_live, __m256 p_far_free, __m256 p_px, __m256 p_py,
		__m256 p_nearest) {
	const PinholeIntrinsics &camera = p_frame.camera;
	const __m256 one = _mm256_set1_ps(1.0f);
	const __m256i u0 = floor_epi32(_mm256_and_ps(p_px, p_live)), v0 = floor_epi32(_mm256_and_ps(p_py, p_live));
	const __m256i last_u = _mm256_set1_epi32(camera.width - 1), last_v = _mm256_set1_epi32(camera.height - 1);
	const __m256i inside = _mm256_and_si256(_mm256_and_si256(_mm256_cmpgt_epi32(u0, _mm256_set1_epi32(-1)), _mm256_cmpgt_epi32(v0, _mm256_set1_epi32(-1))),
			_mm256_and_si256(_mm256_cmpgt_epi32(last_u, u0), _mm256_cmpgt_epi32(last_v, v0)));
	const __m256 four = _mm256_andnot_ps(p_far_free, _mm256_and_ps(p_live, _mm256_castsi256_ps(inside)));
	__m256 depth = p_nearest;
	if (lanes(four) != 0) {
		const __m256i i00 = _mm256_add_epi32(_mm256_mullo_epi32(v0, _mm256_set1_epi32(int(p_frame.depth_stride))), u0);
		const __m256i i01 = _mm256_add_epi32(i00, _mm256_set1_epi32(int(p_frame.depth_stride)));
		const __m256i one_i = _mm256_set1_epi32(1);
		const __m256 d00 = gather(p_frame.depth, i00, four), d10 = gather(p_frame.depth, _mm256_add_epi32(i00, one_i), four);
		const __m256 d01 = gather(p_frame.depth, i01, four), d11 = gather(p_frame.depth, _mm256_add_epi32(i01, one_i), four);
		const __m256 lo = _mm256_min_ps(_mm256_min_ps(d00, d10), _mm256_min_ps(d01, d11)); // NaN lanes fail the sum test
		const __m256 hi = _mm256_max_ps(_mm256_max_ps(d00, d10), _mm256_max_ps(d01, d11));
		const __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(d00, d10), d01), d11);
		const __m256 agree = _mm256_and_ps(four, _mm256_and_ps(_mm256_cmp_ps(sum, sum, _CMP_ORD_Q),
															  _mm256_cmp_ps(_mm256_sub_ps(hi, lo), _mm256_set1_ps(0.5f * p_frame.truncation_m), _CMP_LT_OQ)));
		const __m256 fx = _mm256_sub_ps(p_px, _mm256_cvtepi32_ps(u0)), fy = _mm256_sub_ps(p_py, _mm256_cvtepi32_ps(v0));
		const __m256 gx = _mm256_sub_ps(one, fx), gy = _mm256_sub_ps(one, fy);
		const __m256 top = _mm256_add_ps(_mm256_mul_ps(d00, gx), _mm256_mul_ps(d10, fx));
		const __m256 bottom = _mm256_add_ps(_mm256_mul_ps(d01, gx), _mm256_mul_ps(d11, fx));
		const __m256 bilinear = _mm256_add_ps(_mm256_mul_ps(top, gy), _mm256_mul_ps(bottom, fy));
		depth = _mm256_blendv_ps(depth, bilinear, agree);
	}
	return depth;
}

// The running averages, as the scalar kernel forms them: the new tsdf, and into r_new_weight the
// new weight.
RP_AVX2 __attribute__((always_inline)) static inline __m256 average_tsdf(__m256 p_eta, __m256 p_truncation, __m256 p_slope, __m256 p_has_plane, __m256 p_old_tsdf,
		__m256i p_old_weight, int p_full_weight, __m256i *r_new_weight) {
	const __m256 one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f);
	const __m256 sdf = min_ordered(_mm256_div_ps(p_eta, p_truncation), one);
	const __m256 c = _mm256_and_ps(min_ordered(p_slope, one), p_has_plane);
	const __m256 scaled = _mm256_mul_ps(_mm256_mul_ps(c, c), _mm256_set1_ps(float(TSDF_WEIGHT_UNIT)));
	const __m256i truncated = _mm256_cvttps_epi32(scaled);
	const __m256 remainder = _mm256_sub_ps(scaled, _mm256_cvtepi32_ps(truncated));
	const __m256i rounded = _mm256_sub_epi32(truncated, _mm256_castps_si256(_mm256_cmp_ps(remainder, half, _CMP_GE_OQ))); // + 1 where set
	const __m256i add = _mm256_max_epi32(rounded, _mm256_set1_epi32(1));
	const __m256 add_f = _mm256_cvtepi32_ps(add);
	const __m256 w = _mm256_cvtepi32_ps(p_old_weight);
	*r_new_weight = _mm256_min_epi32(_mm256_add_epi32(p_old_weight, add), _mm256_set1_epi32(p_full_weight));
	return _mm256_div_ps(_mm256_add_ps(_mm256_mul_ps(p_old_tsdf, w), _mm256_mul_ps(sdf, add_f)), _mm256_add_ps(w, add_f));
}

// The p_changed lanes' tsdf and weight written back, and the p_colour lanes' colour blended in
// from pixel (p_u, p_v).
RP_AVX2 __attribute__((always_inline)) static inline void store_row(const TsdfFrameView &p_frame, int p_changed, int p_colour, __m256 p_new_tsdf,
		__m256i p_new_weight, __m256i p_u, __m256i p_v, TsdfVoxel *r_voxels) {
	alignas(32) float tsdf_out[8];
	alignas(32) int weight_out[8], u_out[8], v_out[8];
	_mm256_store_ps(tsdf_out, p_new_tsdf);
	_mm256_store_si256(reinterpret_cast<__m256i *>(weight_out), p_new_weight);
	if (p_colour != 0) {
		_mm256_store_si256(reinterpret_cast<__m256i *>(u_out), p_u);
		_mm256_store_si256(reinterpret_cast<__m256i *>(v_out), p_v);
	}
	for (int i = 0; i < 8; i++) {
		if (!(p_changed & (1 << i))) {
			continue;
		}
		TsdfVoxel &voxel = r_voxels[i];
		voxel.tsdf = tsdf_out[i];
		voxel.weight = uint16_t(weight_out[i]);
		if (p_colour & (1 << i)) {
			tsdf_blend_color(p_frame, u_out[i], v_out[i], &voxel);
		}
	}
}

} // namespace

RP_AVX2 bool tsdf_update_row_simd(const TsdfFrameView &p_frame, const glm::vec3 &p_row_origin, const glm::vec3 &p_step_x, TsdfVoxel *r_voxels) {
	static_assert(TSDF_BLOCK_SIDE == 8 && sizeof(TsdfVoxel) == 12, "eight 12-byte voxels per row");
	const __m256 lane = _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
	const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f);
	// The voxels' points: row origin + x * step, as the scalar loop forms them.
	const __m256 x = _mm256_add_ps(_mm256_set1_ps(p_row_origin.x), _mm256_mul_ps(lane, _mm256_set1_ps(p_step_x.x)));
	const __m256 y = _mm256_add_ps(_mm256_set1_ps(p_row_origin.y), _mm256_mul_ps(lane, _mm256_set1_ps(p_step_x.y)));
	const __m256 z = _mm256_add_ps(_mm256_set1_ps(p_row_origin.z), _mm256_mul_ps(lane, _mm256_set1_ps(p_step_x.z)));
	const PinholeIntrinsics &camera = p_frame.camera;
	__m256 live = _mm256_cmp_ps(z, zero, _CMP_GT_OQ);
	if (lanes(live) == 0) {
		return false;
	}
	// PinholeIntrinsics::project: fx * x / z + cx.
	const __m256 px = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(_mm256_set1_ps(camera.fx), x), z), _mm256_set1_ps(camera.cx));
	const __m256 py = _mm256_add_ps(_mm256_div_ps(_mm256_mul_ps(_mm256_set1_ps(camera.fy), y), z), _mm256_set1_ps(camera.cy));
	const __m256 us = _mm256_add_ps(px, half), vs = _mm256_add_ps(py, half);
	const __m256 width = _mm256_set1_ps(float(camera.width)), height = _mm256_set1_ps(float(camera.height));
	live = _mm256_and_ps(live, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(us, zero, _CMP_GE_OQ), _mm256_cmp_ps(vs, zero, _CMP_GE_OQ)),
										_mm256_and_ps(_mm256_cmp_ps(us, width, _CMP_LT_OQ), _mm256_cmp_ps(vs, height, _CMP_LT_OQ))));
	if (lanes(live) == 0) {
		return false;
	}
	const __m256i u = _mm256_cvttps_epi32(_mm256_and_ps(us, live)), v = _mm256_cvttps_epi32(_mm256_and_ps(vs, live));
	const __m256i depth_index = _mm256_add_epi32(_mm256_mullo_epi32(v, _mm256_set1_epi32(int(p_frame.depth_stride))), u);
	const __m256 nearest = gather(p_frame.depth, depth_index, live);
	live = _mm256_and_ps(live, _mm256_cmp_ps(nearest, nearest, _CMP_ORD_Q)); // a reading
	live = _mm256_and_ps(live, _mm256_cmp_ps(_mm256_sub_ps(nearest, z), _mm256_set1_ps(-p_frame.behind_limit_m), _CMP_GE_OQ));
	if (lanes(live) == 0) {
		return false;
	}
	const __m256i slope_index = _mm256_add_epi32(_mm256_mullo_epi32(v, _mm256_set1_epi32(int(p_frame.slope_stride))), u);
	const __m256 slope = gather(p_frame.slope, slope_index, live);
	const __m256 has_plane = _mm256_cmp_ps(slope, _mm256_set1_ps(p_frame.min_slope), _CMP_GE_OQ); // false for NaN
	const __m256 factor = _mm256_blendv_ps(one, slope, has_plane);
	const __m256 truncation = _mm256_set1_ps(p_frame.truncation_m), neg_truncation = _mm256_set1_ps(-p_frame.truncation_m);
	// The voxels' tsdf and weight (the 32-bit word after tsdf: weight, then color_weight).
	const float *voxel_words = reinterpret_cast<const float *>(r_voxels);
	const __m256i tsdf_index = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
	const __m256 old_tsdf = _mm256_i32gather_ps(voxel_words, tsdf_index, 4);
	const __m256i old_weight = _mm256_and_si256(_mm256_i32gather_epi32(reinterpret_cast<const int *>(r_voxels), _mm256_add_epi32(tsdf_index, _mm256_set1_epi32(1)), 4),
			_mm256_set1_epi32(0xFFFF));
	const int full_weight = int(p_frame.max_weight) * TSDF_WEIGHT_UNIT;
	// Lanes in free space beyond the band whatever the bilinear depth: their tsdf goes to exactly
	// +1 and they take no colour, so the four depth reads of the bilinear depth change nothing.
	__m256 far_free = zero;
	if (p_frame.early_exits) {
		live = skip_early_exits(p_frame, live, z, nearest, factor, has_plane, old_tsdf, old_weight, full_weight, &far_free);
		if (lanes(live) == 0) {
			return false;
		}
	}
	const __m256 depth = bilinear_depth(p_frame, live, far_free, px, py, nearest);
	const __m256 eta = _mm256_mul_ps(_mm256_sub_ps(depth, z), factor);
	live = _mm256_andnot_ps(_mm256_or_ps(_mm256_cmp_ps(eta, neg_truncation, _CMP_LT_OQ), _mm256_andnot_ps(has_plane, _mm256_cmp_ps(eta, truncation, _CMP_LT_OQ))),
			live);
	const int changed = lanes(live);
	if (changed == 0) {
		return false;
	}
	__m256i new_weight;
	const __m256 new_tsdf = average_tsdf(eta, truncation, slope, has_plane, old_tsdf, old_weight, full_weight, &new_weight);
	const __m256 in_band = _mm256_cmp_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), eta), _mm256_set1_ps(p_frame.color_band_m), _CMP_LT_OQ);
	const int colour = lanes(in_band) & changed;
	store_row(p_frame, changed, colour, new_tsdf, new_weight, u, v, r_voxels);
	return true;
}

#else

bool tsdf_simd_available() {
	return false;
}

bool tsdf_update_row_simd(const TsdfFrameView &, const glm::vec3 &, const glm::vec3 &, TsdfVoxel *) {
	return false;
}

#endif

} // namespace roomprobe
