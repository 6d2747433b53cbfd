#include "tsdf_integrate_gpu.h"

#include "depth_pyramid.h"

#include <spirv/depth_smooth.h>
#include <spirv/tsdf_integrate.h>
#include <spirv/tsdf_slope.h>

#include <algorithm>
#include <cstring>

namespace roomprobe {

namespace {

// tsdf_integrate.comp's push constants.
struct Push {
	float fx, fy, cx, cy;
	int32_t width, height;
	float step[9];
	float min_slope, truncation_m, color_band_m, behind_limit_m;
	uint32_t full_weight, max_color_weight, early_exits;
	uint32_t slope_offset, rgb_offset;
	uint32_t first_block;
};
static_assert(sizeof(Push) == 25 * 4);

// depth_smooth.comp's and tsdf_slope.comp's push constants.
struct SmoothPush {
	uint32_t width, height, in_offset, out_offset;
	int32_t radius;
	float band_m;
};
struct SlopePush {
	float fx, fy, cx, cy;
	int32_t width, height;
	uint32_t depth_offset, slope_offset;
	float max_jump_m;
};

constexpr uint32_t GROUP_SIDE = 8; // the per-pixel kernels' local size, x and y
static_assert(sizeof(TsdfVoxel) == 12 && sizeof(TsdfGpuBlock) == 16, "tsdf_integrate.comp reads these layouts");

} // namespace

std::unique_ptr<TsdfIntegratorGpu> TsdfIntegratorGpu::create(std::shared_ptr<ComputeDevice> p_device, size_t p_pool_blocks, std::string *r_error,
		size_t p_window_blocks) {
	if (!p_device) {
		*r_error = "no compute device";
		return nullptr;
	}
	constexpr size_t BLOCK_BYTES = TSDF_BLOCK_VOXELS * sizeof(TsdfVoxel); // 6 KiB: a multiple of any offset alignment up to 2 KiB
	const size_t reach = p_device->limits().maxStorageBufferRange / BLOCK_BYTES;
	if (reach == 0 || p_device->limits().minStorageBufferOffsetAlignment > 2048) {
		*r_error = "the device's storage buffers cannot hold a voxel block";
		return nullptr;
	}
	std::unique_ptr<TsdfIntegratorGpu> out(new TsdfIntegratorGpu());
	out->compute = std::move(p_device);
	out->capacity_blocks = std::max<size_t>(p_pool_blocks, 1);
	out->window_blocks = std::min(p_window_blocks > 0 ? p_window_blocks : reach, reach);
	out->kernel = out->compute->make_kernel(spirv::tsdf_integrate, sizeof(spirv::tsdf_integrate) / sizeof(uint32_t), 4, sizeof(Push), r_error, "tsdf_integrate");
	out->smooth_kernel = out->kernel ? out->compute->make_kernel(spirv::depth_smooth, sizeof(spirv::depth_smooth) / sizeof(uint32_t), 2, sizeof(SmoothPush), r_error, "depth_smooth") : nullptr;
	out->slope_kernel = out->smooth_kernel ? out->compute->make_kernel(spirv::tsdf_slope, sizeof(spirv::tsdf_slope) / sizeof(uint32_t), 1, sizeof(SlopePush), r_error, "tsdf_slope") : nullptr;
	if (!out->slope_kernel) {
		return nullptr;
	}
	const size_t pool_bytes = out->capacity_blocks * BLOCK_BYTES;
	out->voxels = out->compute->make_buffer(pool_bytes, GpuAccess::HostReads, r_error); // the CPU allocates, meshes and reads it
	if (!out->voxels) {
		*r_error = "the voxel pool (" + std::to_string(pool_bytes >> 20) + " MiB, max_blocks " + std::to_string(p_pool_blocks) + "): " + *r_error;
		return nullptr;
	}
	return out;
}

GpuWindow TsdfIntegratorGpu::pool_window(size_t p_window) const {
	constexpr size_t BLOCK_BYTES = TSDF_BLOCK_VOXELS * sizeof(TsdfVoxel);
	const size_t first = p_window * window_blocks;
	return GpuWindow{ first * BLOCK_BYTES, std::min(window_blocks, capacity_blocks - first) * BLOCK_BYTES };
}

bool TsdfIntegratorGpu::ensure(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error) const {
	return compute->ensure_buffer(r_buffer, p_bytes, p_access, r_error, p_bytes / 4 /* the block list changes length every frame */);
}

void TsdfIntegratorGpu::upload_frame(const TsdfFrameView &p_frame, size_t p_rgb_offset) {
	// No NaN on the device: no reading is depth 0.
	uint32_t *words = static_cast<uint32_t *>(frame->data());
	float *depth = reinterpret_cast<float *>(words);
	const int w = p_frame.camera.width, h = p_frame.camera.height;
	for (int v = 0; v < h; v++) {
		const float *d = p_frame.depth + size_t(v) * p_frame.depth_stride;
		for (int u = 0; u < w; u++) {
			*depth++ = d[u] == d[u] ? d[u] : 0.0f;
		}
	}
	uint8_t *rgb = reinterpret_cast<uint8_t *>(words + p_rgb_offset);
	for (int v = 0; v < h; v++) {
		std::memcpy(rgb + size_t(v) * size_t(w) * 3, p_frame.rgb + size_t(v) * p_frame.rgb_stride, size_t(w) * 3);
	}
}

void TsdfIntegratorGpu::add_slope_dispatches(const TsdfFrameView &p_frame, int p_radius, size_t p_slope_offset, std::vector<GpuDispatch> *r_batch) {
	const PinholeIntrinsics &camera = p_frame.camera;
	const uint32_t w = uint32_t(camera.width), h = uint32_t(camera.height);
	const size_t pixels = size_t(w) * size_t(h);
	GpuDispatch dispatch;
	dispatch.groups_x = (w + GROUP_SIDE - 1) / GROUP_SIDE;
	dispatch.groups_y = (h + GROUP_SIDE - 1) / GROUP_SIDE;
	uint32_t tangents_from = 0; // the depth the tangent planes are taken on: the clean one, or smoothed after it
	if (p_radius > 0) {
		dispatch.kernel = smooth_kernel.get();
		dispatch.buffers = { weights.get(), frame.get() };
		dispatch.set_push(SmoothPush{ w, h, 0u, uint32_t(pixels), int32_t(p_radius), p_frame.truncation_m });
		r_batch->push_back(dispatch);
		tangents_from = uint32_t(pixels);
	}
	dispatch.kernel = slope_kernel.get();
	dispatch.buffers = { frame.get() };
	dispatch.set_push(SlopePush{ camera.fx, camera.fy, camera.cx, camera.cy, int32_t(w), int32_t(h), tangents_from, uint32_t(p_slope_offset),
			0.5f * p_frame.truncation_m });
	r_batch->push_back(dispatch);
}

bool TsdfIntegratorGpu::integrate(const TsdfFrameView &p_frame, int p_slope_smoothing_px, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y, const glm::vec3 &p_step_z,
		const std::vector<TsdfGpuBlock> &p_blocks, std::vector<uint32_t> *r_flags, std::string *r_error) {
	r_flags->assign(p_blocks.size(), 0);
	if (p_blocks.empty()) {
		return true;
	}
	const size_t pixels = size_t(p_frame.camera.width) * size_t(p_frame.camera.height);
	// The frame's words: the clean depth, the smoothed depth, the slope factors, then the RGB bytes.
	const size_t slope_offset = 2 * pixels, rgb_offset = 3 * pixels;
	const size_t frame_words = rgb_offset + (pixels * 3 + 3) / 4;
	// The list by window of the pool, each block's slot counted from its window's start.
	const size_t windows = pool_windows();
	std::vector<size_t> first(windows + 1, 0);
	for (const TsdfGpuBlock &block : p_blocks) {
		first[block.slot / window_blocks + 1]++;
	}
	for (size_t w = 0; w < windows; w++) {
		first[w + 1] += first[w];
	}
	if (!ensure(&blocks, p_blocks.size() * sizeof(TsdfGpuBlock), GpuAccess::DeviceReads, r_error) ||
			!ensure(&frame, frame_words * sizeof(uint32_t), GpuAccess::DeviceReads, r_error) ||
			!ensure(&flags, p_blocks.size() * sizeof(uint32_t), GpuAccess::HostReads, r_error)) {
		return false;
	}
	const int radius = std::max(0, p_slope_smoothing_px);
	if (weights_radius != radius) {
		const std::vector<float> table = smoothing_weights(std::max(radius, 1));
		if (!ensure(&weights, table.size() * sizeof(float), GpuAccess::DeviceReads, r_error)) {
			return false;
		}
		std::memcpy(weights->data(), table.data(), table.size() * sizeof(float));
		weights_radius = radius;
	}
	TsdfGpuBlock *listed = static_cast<TsdfGpuBlock *>(blocks->data());
	std::vector<size_t> next(first.begin(), first.end() - 1), entry_of(p_blocks.size());
	for (size_t i = 0; i < p_blocks.size(); i++) {
		const size_t w = p_blocks[i].slot / window_blocks;
		entry_of[i] = next[w]++;
		listed[entry_of[i]] = p_blocks[i];
		listed[entry_of[i]].slot = uint32_t(p_blocks[i].slot - w * window_blocks);
	}
	upload_frame(p_frame, rgb_offset);
	Push push{ p_frame.camera.fx, p_frame.camera.fy, p_frame.camera.cx, p_frame.camera.cy, p_frame.camera.width, p_frame.camera.height,
		{ p_step_x.x, p_step_x.y, p_step_x.z, p_step_y.x, p_step_y.y, p_step_y.z, p_step_z.x, p_step_z.y, p_step_z.z }, p_frame.min_slope,
		p_frame.truncation_m, p_frame.color_band_m, p_frame.behind_limit_m, uint32_t(p_frame.max_weight) * TSDF_WEIGHT_UNIT, p_frame.max_color_weight,
		p_frame.early_exits ? 1u : 0u, uint32_t(slope_offset), uint32_t(rgb_offset), 0u };
	std::vector<GpuDispatch> batch;
	add_slope_dispatches(p_frame, radius, slope_offset, &batch);
	for (size_t w = 0; w < windows; w++) {
		const size_t count = first[w + 1] - first[w];
		if (count == 0) {
			continue;
		}
		if (count > compute->limits().maxComputeWorkGroupCount[0]) {
			*r_error = std::to_string(count) + " blocks in one frame exceed the device's workgroup count";
			return false;
		}
		GpuDispatch dispatch;
		dispatch.kernel = kernel.get();
		dispatch.buffers = { voxels.get(), blocks.get(), frame.get(), flags.get() };
		dispatch.windows = { pool_window(w) };
		push.first_block = uint32_t(first[w]);
		dispatch.set_push(push);
		dispatch.groups_x = uint32_t(count);
		batch.push_back(std::move(dispatch));
	}
	*r_error = compute->run(batch);
	if (!r_error->empty()) {
		return false;
	}
	const uint32_t *out = static_cast<const uint32_t *>(flags->data());
	for (size_t i = 0; i < p_blocks.size(); i++) {
		(*r_flags)[i] = out[entry_of[i]];
	}
	return true;
}

} // namespace roomprobe
