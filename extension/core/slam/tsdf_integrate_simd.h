#pragma once
// The per-voxel update of tsdf_update_voxel_at (tsdf_kernels.h), eight voxels of a block's row at
// a time with AVX2, chosen at run time: the core is built for baseline x86-64 (users' CPUs vary),
// and this one file's functions carry the AVX2 target themselves. The lanes do the same float
// operations in the same order as the scalar kernel, so the voxels come out bit-identical
// (test_slam_tsdf checks it); colour, rare (within color_band of the surface), stays scalar.

#include "slam/tsdf_kernels.h"

#include <glm/vec3.hpp>

namespace roomprobe {

// Whether this CPU runs tsdf_update_row_simd (AVX2); false on other architectures.
bool tsdf_simd_available();

// Updates the TSDF_BLOCK_SIDE voxels of one row of a block, voxel x at p_row_origin + x *
// p_step_x in the camera's frame, as tsdf_update_voxel_at does each. True when any changed.
// Only where tsdf_simd_available().
bool tsdf_update_row_simd(const TsdfFrameView &p_frame, const glm::vec3 &p_row_origin, const glm::vec3 &p_step_x, TsdfVoxel *r_voxels);

} // namespace roomprobe
