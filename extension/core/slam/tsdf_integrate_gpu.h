#pragma once
// TSDF integration on a Vulkan compute device (issue #40): the voxel pool lives in memory the
// device and the host share (mapped, host-cached where the device has it), so the blocks the
// device updates are the ones the CPU's raycasts, copies and meshing read, with no copy either
// way. TsdfVolume keeps choosing what to update on the CPU (the blocks along the readings' bands
// allocated in its hash, the blocks in view, the culling) and hands the list here; the device
// makes the slope factors (depth_smooth.comp, then tsdf_slope.comp: tsdf_depth_slope) and runs
// tsdf_update_voxel_at on every voxel of it (tsdf_integrate.comp, one workgroup a block), in
// one batch.
//
// Tolerance against the CPU: the same operations in the same order, with multiply-adds kept
// apart (`precise`), so a device whose division is correctly rounded (lavapipe's is) gives the
// CPU's voxels bit for bit; Vulkan lets a GPU's division be 2.5 ulp off, which moves a tsdf by
// float rounding and, where a voxel projects onto a pixel boundary, picks the neighbouring pixel
// (tests/core/test_gpu_integration.cpp holds both).

#include "tsdf_kernels.h"

#include <gpu/compute_device.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace roomprobe {

// A block to update: its pool slot and its voxel (0, 0, 0) in the camera's frame, metres.
struct TsdfGpuBlock {
	uint32_t slot = 0;
	float x = 0.0f, y = 0.0f, z = 0.0f;
};

class TsdfIntegratorGpu {
public:
	// Per block in integrate's r_flags.
	static constexpr uint32_t CHANGED = 1; // a voxel changed
	static constexpr uint32_t SATURATED = 2; // every voxel is now at +1 with the full weight

	// A pool of p_pool_blocks blocks on p_device (uninitialised: the volume writes TsdfVoxel's
	// defaults into a slot as it allocates it), and the kernel. The kernel binds the pool a window
	// at a time, p_window_blocks blocks each (0: as many as one binding reaches on the device,
	// maxStorageBufferRange; tests ask for fewer). Null, with r_error, when the device cannot: no
	// memory for the pool, or the kernel refused.
	static std::unique_ptr<TsdfIntegratorGpu> create(std::shared_ptr<ComputeDevice> p_device, size_t p_pool_blocks, std::string *r_error,
			size_t p_window_blocks = 0);

	// The pool, slot s at [s * 512, s * 512 + 512), valid as long as this integrator.
	TsdfVoxel *pool() const { return static_cast<TsdfVoxel *>(voxels->data()); }
	size_t pool_blocks() const { return capacity_blocks; }

	// One frame into p_blocks (p_frame as the CPU's update reads it, less its slope factors,
	// which are made here on the depth smoothed over p_slope_smoothing_px (TsdfOptions'); the
	// grid's axes in the camera's frame as p_step_*): r_flags gets CHANGED and SATURATED per block
	// (one dispatch per window of the pool the blocks lie in, all in one batch). False with
	// r_error when a buffer or the dispatch failed; the pool may then hold part of the frame.
	bool integrate(const TsdfFrameView &p_frame, int p_slope_smoothing_px, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y, const glm::vec3 &p_step_z,
			const std::vector<TsdfGpuBlock> &p_blocks, std::vector<uint32_t> *r_flags, std::string *r_error);

	const ComputeDevice &device() const { return *compute; }
	// The pool as the kernels bind it: one buffer, blocks_per_window() blocks per binding, the
	// last window shorter; pool_window(w) is window w's part of the buffer.
	const GpuBuffer &pool_buffer() const { return *voxels; }
	size_t blocks_per_window() const { return window_blocks; }
	size_t pool_windows() const { return (capacity_blocks + window_blocks - 1) / window_blocks; }
	GpuWindow pool_window(size_t p_window) const;

private:
	TsdfIntegratorGpu() = default;
	bool ensure(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error) const;
	void upload_frame(const TsdfFrameView &p_frame, size_t p_rgb_offset);
	// The batch's first dispatches: the smoothing (when p_radius > 0) and the slope factors.
	void add_slope_dispatches(const TsdfFrameView &p_frame, int p_radius, size_t p_slope_offset, std::vector<GpuDispatch> *r_batch);

	std::shared_ptr<ComputeDevice> compute; // outlives the buffers below
	std::unique_ptr<GpuKernel> kernel, smooth_kernel, slope_kernel;
	std::unique_ptr<GpuBuffer> voxels, blocks, frame, flags, weights;
	int weights_radius = -1;
	size_t capacity_blocks = 0;
	size_t window_blocks = 0;
};

} // namespace roomprobe
