// IcpReducerGpu::build_frame (icp_reduce_gpu.h): the frame's pyramid made on the device, in one
// batch: the finest level smoothed, each coarser level downsampled from the one above (depth and
// intensity), then every level's vertices, normals and flags written where icp_reduce.comp reads them.
#include "icp_reduce_gpu.h"

#include <spirv/depth_downsample.h>
#include <spirv/depth_smooth.h>
#include <spirv/depth_surface.h>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace roomprobe {

namespace {

constexpr uint32_t GROUP_SIDE = 8; // the pyramid kernels' local size, x and y

template <typename Push>
GpuDispatch dispatch_of(const GpuKernel *p_kernel, std::vector<const GpuBuffer *> p_buffers, const Push &p_push, uint32_t p_width, uint32_t p_height) {
	GpuDispatch dispatch;
	dispatch.kernel = p_kernel;
	dispatch.buffers = std::move(p_buffers);
	dispatch.set_push(p_push);
	dispatch.groups_x = (p_width + GROUP_SIDE - 1) / GROUP_SIDE;
	dispatch.groups_y = (p_height + GROUP_SIDE - 1) / GROUP_SIDE;
	return dispatch;
}

// The kernels' push constants.
struct SmoothPush {
	uint32_t width, height, in_offset, out_offset;
	int32_t radius;
	float band_m;
};
struct DownsamplePush {
	uint32_t in_width, in_height, in_offset, out_width, out_height, out_offset, intensity_in_offset, intensity_out_offset, has_intensity;
	float band_m;
};
struct SurfacePush {
	uint32_t width, height, depth_offset, intensity_offset, has_intensity, stride, columns, rows, frame_offset;
	float fx, fy, cx, cy, max_jump_relative;
};

} // namespace

bool IcpReducerGpu::make_pyramid_kernels(std::string *r_error) {
	if (surface_kernel) {
		return true;
	}
	smooth_kernel = compute->make_kernel(spirv::depth_smooth, sizeof(spirv::depth_smooth) / sizeof(uint32_t), 2, sizeof(SmoothPush), r_error, "depth_smooth");
	downsample_kernel = compute->make_kernel(spirv::depth_downsample, sizeof(spirv::depth_downsample) / sizeof(uint32_t), 2, sizeof(DownsamplePush), r_error, "depth_downsample");
	surface_kernel = compute->make_kernel(spirv::depth_surface, sizeof(spirv::depth_surface) / sizeof(uint32_t), 3, sizeof(SurfacePush), r_error, "depth_surface");
	return smooth_kernel && downsample_kernel && surface_kernel;
}

bool IcpReducerGpu::build_frame(const cv::Mat &p_clean_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, int p_levels, float p_band_m,
		const SurfaceOptions &p_surface, int p_finest_stride, std::string *r_error) {
	if (p_clean_depth_m.type() != CV_32FC1 || p_clean_depth_m.cols != p_camera.width || p_clean_depth_m.rows != p_camera.height || p_levels < 1) {
		*r_error = "build_frame needs CV_32FC1 depth of the camera's size and a level";
		return false;
	}
	const size_t frame_floats_needed = plan_levels(p_camera, p_levels, p_finest_stride);
	// Depth: the clean input, then level 0 smoothed, then the coarser levels; intensity: level by level.
	std::vector<size_t> depth_at(static_cast<size_t>(p_levels) + 1), intensity_at(static_cast<size_t>(p_levels));
	size_t depth_floats = size_t(p_camera.width) * size_t(p_camera.height), intensity_floats = 0;
	for (int l = 0; l < p_levels; l++) {
		const PinholeIntrinsics camera = p_camera.level(l);
		depth_at[size_t(l) + 1] = depth_floats;
		intensity_at[size_t(l)] = intensity_floats;
		depth_floats += size_t(camera.width) * size_t(camera.height);
		intensity_floats += size_t(camera.width) * size_t(camera.height);
	}
	const int radius = std::max(0, p_surface.smoothing_radius_px);
	const bool colour = !p_rgb.empty();
	// All four stay on the device (the host only writes the inputs): the pyramid feeds icp_reduce there.
	const GpuAccess d = GpuAccess::DeviceReads;
	if (!make_pyramid_kernels(r_error) || !ensure(&frame, frame_floats_needed * sizeof(float), d, r_error) ||
			!ensure(&depth, depth_floats * sizeof(float), d, r_error) || !ensure(&intensity, intensity_floats * sizeof(float), d, r_error) ||
			!ensure(&weights, size_t(2 * radius + 1) * size_t(2 * radius + 1) * sizeof(float), d, r_error)) {
		return false;
	}
	if (weights_radius != radius) {
		const std::vector<float> table = smoothing_weights(radius);
		std::memcpy(weights->data(), table.data(), table.size() * sizeof(float));
		weights_radius = radius;
	}
	// No NaN on the device: a missing reading is 0.
	float *clean = static_cast<float *>(depth->data());
	for (int y = 0; y < p_clean_depth_m.rows; y++) {
		const float *row = p_clean_depth_m.ptr<float>(y);
		for (int x = 0; x < p_clean_depth_m.cols; x++) {
			*clean++ = row[x] > 0.0f ? row[x] : 0.0f;
		}
	}
	if (colour) {
		const cv::Mat level0 = intensity_of(p_rgb);
		CV_Assert(level0.isContinuous() && level0.cols == p_camera.width && level0.rows == p_camera.height);
		std::memcpy(intensity->data(), level0.ptr<float>(), size_t(level0.total()) * sizeof(float));
	}

	std::vector<GpuDispatch> batch;
	const uint32_t w = uint32_t(p_camera.width), h = uint32_t(p_camera.height);
	batch.push_back(dispatch_of(smooth_kernel.get(), { weights.get(), depth.get() },
			SmoothPush{ w, h, 0u, uint32_t(depth_at[1]), int32_t(radius), p_surface.smoothing_band_m }, w, h));
	for (int l = 1; l < p_levels; l++) {
		const PinholeIntrinsics above = p_camera.level(l - 1), here = p_camera.level(l);
		const DownsamplePush push{ uint32_t(above.width), uint32_t(above.height), uint32_t(depth_at[size_t(l)]), uint32_t(here.width), uint32_t(here.height),
			uint32_t(depth_at[size_t(l) + 1]), uint32_t(intensity_at[size_t(l) - 1]), uint32_t(intensity_at[size_t(l)]), colour ? 1u : 0u, p_band_m };
		batch.push_back(dispatch_of(downsample_kernel.get(), { depth.get(), intensity.get() }, push, uint32_t(here.width), uint32_t(here.height)));
	}
	for (int l = 0; l < p_levels; l++) {
		const PinholeIntrinsics camera = p_camera.level(l);
		const Level &level = levels[size_t(l)];
		const SurfacePush push{ uint32_t(camera.width), uint32_t(camera.height), uint32_t(depth_at[size_t(l) + 1]), uint32_t(intensity_at[size_t(l)]),
			colour ? 1u : 0u, uint32_t(l == 0 ? p_finest_stride : 1), uint32_t(level.cols), uint32_t(level.rows), uint32_t(level.first_float),
			camera.fx, camera.fy, camera.cx, camera.cy, p_surface.max_jump_relative };
		batch.push_back(dispatch_of(surface_kernel.get(), { depth.get(), intensity.get(), frame.get() }, push, uint32_t(level.cols), uint32_t(level.rows)));
	}
	*r_error = compute->run(batch);
	return r_error->empty();
}

} // namespace roomprobe
