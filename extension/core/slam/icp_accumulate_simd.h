#pragma once
// ICP's point-to-plane rows (icp_correspondence in icp_kernels.h, geometry only), eight pixels of
// an image row at a time with AVX2, chosen at run time like the TSDF's row kernel
// (tsdf_integrate_simd.h): the core is built for baseline x86-64, and only this file's functions
// carry the AVX2 target. Each lane does the scalar kernel's float operations in its order, so a
// pixel's row of the system is the scalar one; only the order of the sums differs (eight lane
// sums per image row, added in double), which moves a level's normal equations by float rounding
// (test_slam_icp_simd checks both). The photometric row stays scalar: it joins a solve only where
// the geometry leaves a direction free.

#include "slam/icp_kernels.h"

namespace roomprobe {

// One image row's share of the normal equations, in the layout icp_tracker.cpp's RowSums and the
// device's rows (icp_reduce.comp) use too.
// sums: the upper triangle of J^T J row by row (21), J^T r (6), the traces of the rows' rotation
// and translation parts, and their unweighted squared residuals (metres^2).
struct IcpRowTotals {
	static constexpr int SUMS = 30;
	double sums[SUMS] = {};
	int inliers = 0;
};

// Whether this CPU runs icp_accumulate_row_simd (AVX2); false on other architectures.
bool icp_simd_available();

// Adds to r_totals the point-to-plane rows of the pixels x = k p_stride_px, k < p_count, of one
// row of a camera-frame vertex and normal map (xyz interleaved, NaN = none). p_count is a multiple
// of 8; the caller takes a row's remainder with the scalar kernel. Only where icp_simd_available().
void icp_accumulate_row_simd(const float *p_vertices, const float *p_normals, int p_count, int p_stride_px, const IcpKernelParams &p_params,
		const IcpModelView &p_model, IcpRowTotals *r_totals);

} // namespace roomprobe
