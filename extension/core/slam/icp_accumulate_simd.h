#pragma once
// ICP's rows (icp_correspondence in icp_kernels.h: point-to-plane and photometric), eight pixels of
// an image row at a time with AVX2, chosen at run time like the TSDF's row kernel
// (tsdf_integrate_simd.h): the core is built for baseline x86-64, and only this file's functions
// carry the AVX2 target. Each lane does the scalar kernel's float operations in its order, so a
// pixel's row of the system is the scalar one; only the order of the sums differs (eight lane
// sums per image row, added in double), which moves a level's normal equations by float rounding
// (test_slam_icp_simd checks both).

#include "slam/icp_kernels.h"

namespace roomprobe {

// One image row's share of the normal equations, as icp_tracker.cpp's RowSums lays them out.
// sums: the upper triangle of J^T J row by row (21), J^T r (6), the traces of the rows' rotation
// and translation parts, and their unweighted squared residuals (metres^2).
struct IcpRowTotals {
	static constexpr int SUMS = 30;
	double sums[SUMS] = {};
	int inliers = 0;
};

// Whether this CPU runs icp_accumulate_row_simd (AVX2); false on other architectures.
bool icp_simd_available();

// Adds to r_totals the rows of the pixels x = k p_stride_px, k < p_count, of one row of a
// camera-frame vertex and normal map (xyz interleaved, NaN = none) and of the frame's intensity
// (in [0, 1], NaN = none; null: no photometric rows, as when the model has no intensity or the
// colour weight is 0). p_count is a multiple of 8; the caller takes a row's remainder with the
// scalar kernel. Only where icp_simd_available().
void icp_accumulate_row_simd(const float *p_vertices, const float *p_normals, const float *p_intensity, int p_count, int p_stride_px,
		const IcpKernelParams &p_params, const IcpModelView &p_model, IcpRowTotals *r_totals);

} // namespace roomprobe
