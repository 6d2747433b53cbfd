#include "slam/icp_accumulate_simd.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define RP_ICP_SIMD 1
#endif

namespace roomprobe {

#ifdef RP_ICP_SIMD

bool icp_simd_available() {
	static const bool available = __builtin_cpu_supports("avx2");
	return available;
}

namespace {

#define RP_AVX2 __attribute__((target("avx2")))
#define RP_INLINE __attribute__((always_inline)) static inline

// Eight vectors, one per lane.
struct Lanes3 {
	__m256 x, y, z;
};

RP_AVX2 RP_INLINE __m256 add(__m256 p_a, __m256 p_b) {
	return _mm256_add_ps(p_a, p_b);
}
RP_AVX2 RP_INLINE __m256 sub(__m256 p_a, __m256 p_b) {
	return _mm256_sub_ps(p_a, p_b);
}
RP_AVX2 RP_INLINE __m256 mul(__m256 p_a, __m256 p_b) {
	return _mm256_mul_ps(p_a, p_b);
}
RP_AVX2 RP_INLINE __m256 all(float p_value) {
	return _mm256_set1_ps(p_value);
}

// glm's m * v: component r is (m[0][r] v.x + m[1][r] v.y) + m[2][r] v.z.
RP_AVX2 RP_INLINE __m256 transformed(const glm::mat3 &p_m, int p_r, const Lanes3 &p_v) {
	return add(add(mul(all(p_m[0][p_r]), p_v.x), mul(all(p_m[1][p_r]), p_v.y)), mul(all(p_m[2][p_r]), p_v.z));
}
RP_AVX2 RP_INLINE Lanes3 transform(const glm::mat3 &p_m, const Lanes3 &p_v) {
	return { transformed(p_m, 0, p_v), transformed(p_m, 1, p_v), transformed(p_m, 2, p_v) };
}

// glm::dot: (a.x b.x + a.y b.y) + a.z b.z.
RP_AVX2 RP_INLINE __m256 dot(const Lanes3 &p_a, const Lanes3 &p_b) {
	return add(add(mul(p_a.x, p_b.x), mul(p_a.y, p_b.y)), mul(p_a.z, p_b.z));
}

// glm::cross.
RP_AVX2 RP_INLINE Lanes3 cross(const Lanes3 &p_a, const Lanes3 &p_b) {
	return { sub(mul(p_a.y, p_b.z), mul(p_b.y, p_a.z)), sub(mul(p_a.z, p_b.x), mul(p_b.z, p_a.x)), sub(mul(p_a.x, p_b.y), mul(p_b.x, p_a.y)) };
}

// The xyz of eight interleaved pixels at float offsets p_index (masked lanes read 0).
RP_AVX2 RP_INLINE Lanes3 gather3(const float *p_base, __m256i p_index, __m256 p_mask) {
	const __m256 zero = _mm256_setzero_ps();
	const __m256i one = _mm256_set1_epi32(1);
	const __m256i two = _mm256_set1_epi32(2);
	return { _mm256_mask_i32gather_ps(zero, p_base, p_index, p_mask, 4),
		_mm256_mask_i32gather_ps(zero, p_base, _mm256_add_epi32(p_index, one), p_mask, 4),
		_mm256_mask_i32gather_ps(zero, p_base, _mm256_add_epi32(p_index, two), p_mask, 4) };
}

RP_AVX2 RP_INLINE __m256 is_number(__m256 p_x) {
	return _mm256_cmp_ps(p_x, p_x, _CMP_ORD_Q);
}

// icp_correspondence's geometry row for eight pixels: the lanes that pair (the mask), their
// jacobians and residuals zeroed elsewhere, and the squared residuals.
struct Rows8 {
	__m256 mask;
	__m256 j[6];
	__m256 residual;
	__m256 squared;
};

RP_AVX2 RP_INLINE Rows8 rows8(const Lanes3 &p_vertex, const Lanes3 &p_normal, const IcpKernelParams &p_params, const IcpModelView &p_model) {
	Rows8 out;
	__m256 mask = _mm256_and_ps(_mm256_cmp_ps(p_vertex.z, _mm256_setzero_ps(), _CMP_GT_OQ), is_number(p_normal.x));
	const Lanes3 offset = transform(p_params.rotation, p_vertex);
	const Lanes3 point = { add(offset.x, all(p_params.translation.x)), add(offset.y, all(p_params.translation.y)), add(offset.z, all(p_params.translation.z)) };
	const Lanes3 normal = transform(p_params.rotation, p_normal);
	const Lanes3 turned = transform(p_model.camera_from_world_rotation, point);
	const glm::vec3 &t = p_model.camera_from_world_translation;
	const Lanes3 in_model = { add(turned.x, all(t.x)), add(turned.y, all(t.y)), add(turned.z, all(t.z)) };
	mask = _mm256_and_ps(mask, _mm256_cmp_ps(in_model.z, _mm256_setzero_ps(), _CMP_GT_OQ));
	const PinholeIntrinsics &camera = p_model.camera;
	const __m256 shifted_x = add(add(_mm256_div_ps(mul(all(camera.fx), in_model.x), in_model.z), all(camera.cx)), all(0.5f));
	const __m256 shifted_y = add(add(_mm256_div_ps(mul(all(camera.fy), in_model.y), in_model.z), all(camera.cy)), all(0.5f));
	mask = _mm256_and_ps(mask, _mm256_and_ps(_mm256_cmp_ps(shifted_x, _mm256_setzero_ps(), _CMP_GT_OQ), _mm256_cmp_ps(shifted_y, _mm256_setzero_ps(), _CMP_GT_OQ)));
	mask = _mm256_and_ps(mask, _mm256_and_ps(_mm256_cmp_ps(shifted_x, all(float(camera.width)), _CMP_LT_OQ),
										   _mm256_cmp_ps(shifted_y, all(float(camera.height)), _CMP_LT_OQ)));
	// Lanes outside read pixel 0, masked.
	const __m256i u = _mm256_cvttps_epi32(_mm256_and_ps(shifted_x, mask));
	const __m256i v = _mm256_cvttps_epi32(_mm256_and_ps(shifted_y, mask));
	const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(v, _mm256_set1_epi32(int(p_model.stride))), _mm256_mullo_epi32(u, _mm256_set1_epi32(3)));
	const Lanes3 model_point = gather3(p_model.points, index, mask);
	const Lanes3 model_normal = gather3(p_model.normals, index, mask);
	mask = _mm256_and_ps(mask, _mm256_and_ps(is_number(model_point.x), is_number(model_normal.x)));
	const Lanes3 difference = { sub(point.x, model_point.x), sub(point.y, model_point.y), sub(point.z, model_point.z) };
	// The scalar kernel drops a pair when the test is true: keep where it is not (NaN kept, as there).
	const float max_squared = p_params.max_distance_m * p_params.max_distance_m;
	mask = _mm256_and_ps(mask, _mm256_cmp_ps(dot(difference, difference), all(max_squared), _CMP_NGT_UQ));
	mask = _mm256_and_ps(mask, _mm256_cmp_ps(dot(normal, model_normal), all(p_params.min_normal_cos), _CMP_NLT_UQ));
	// depth_noise_weight.
	const __m256 d = sub(p_vertex.z, all(p_params.noise_c_m));
	const __m256 sigma = add(all(p_params.noise_a_m), mul(mul(all(p_params.noise_b_per_m2), d), d));
	const __m256 reference = all(p_params.noise_reference_sigma_m);
	const __m256 weight = _mm256_blendv_ps(all(1.0f), _mm256_div_ps(reference, sigma), _mm256_cmp_ps(sigma, reference, _CMP_GT_OQ));
	const __m256 residual = dot(model_normal, difference);
	const Lanes3 moment = cross(offset, model_normal);
	out.mask = mask;
	out.j[0] = _mm256_and_ps(mul(moment.x, weight), mask);
	out.j[1] = _mm256_and_ps(mul(moment.y, weight), mask);
	out.j[2] = _mm256_and_ps(mul(moment.z, weight), mask);
	out.j[3] = _mm256_and_ps(mul(model_normal.x, weight), mask);
	out.j[4] = _mm256_and_ps(mul(model_normal.y, weight), mask);
	out.j[5] = _mm256_and_ps(mul(model_normal.z, weight), mask);
	out.residual = _mm256_and_ps(mul(residual, weight), mask);
	out.squared = _mm256_and_ps(mul(residual, residual), mask);
	return out;
}

// RowSums::add and accumulate's traces, per lane.
RP_AVX2 RP_INLINE void add_rows(const Rows8 &p_rows, __m256 *r_sums) {
	int k = 0;
	for (int a = 0; a < 6; ++a) {
		for (int b = a; b < 6; ++b) {
			r_sums[k] = add(r_sums[k], mul(p_rows.j[a], p_rows.j[b]));
			++k;
		}
	}
	for (int a = 0; a < 6; ++a) {
		r_sums[21 + a] = add(r_sums[21 + a], mul(p_rows.j[a], p_rows.residual));
	}
	const __m256 *j = p_rows.j;
	r_sums[27] = add(r_sums[27], add(add(mul(j[0], j[0]), mul(j[1], j[1])), mul(j[2], j[2])));
	r_sums[28] = add(r_sums[28], add(add(mul(j[3], j[3]), mul(j[4], j[4])), mul(j[5], j[5])));
	r_sums[29] = add(r_sums[29], p_rows.squared);
}

} // namespace

RP_AVX2 void icp_accumulate_row_simd(const float *p_vertices, const float *p_normals, int p_count, int p_stride_px, const IcpKernelParams &p_params,
		const IcpModelView &p_model, IcpRowTotals *r_totals) {
	__m256 sums[IcpRowTotals::SUMS];
	for (__m256 &sum : sums) {
		sum = _mm256_setzero_ps();
	}
	int inliers = 0;
	const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
	const __m256i step = _mm256_set1_epi32(3 * p_stride_px);
	const __m256 every = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
	for (int k = 0; k + 8 <= p_count; k += 8) {
		const __m256i index = _mm256_mullo_epi32(_mm256_add_epi32(_mm256_set1_epi32(k), lane), step);
		const Lanes3 vertex = gather3(p_vertices, index, every);
		const Lanes3 normal = gather3(p_normals, index, every);
		const Rows8 rows = rows8(vertex, normal, p_params, p_model);
		const int paired = _mm256_movemask_ps(rows.mask);
		if (paired == 0) {
			continue;
		}
		inliers += __builtin_popcount(unsigned(paired));
		add_rows(rows, sums);
	}
	alignas(32) float lanes[8];
	for (int s = 0; s < IcpRowTotals::SUMS; ++s) {
		_mm256_store_ps(lanes, sums[s]);
		double total = 0.0;
		for (float value : lanes) {
			total += double(value);
		}
		r_totals->sums[s] += total;
	}
	r_totals->inliers += inliers;
}

#else

bool icp_simd_available() {
	return false;
}

void icp_accumulate_row_simd(const float *, const float *, int, int, const IcpKernelParams &, const IcpModelView &, IcpRowTotals *) {}

#endif

} // namespace roomprobe
