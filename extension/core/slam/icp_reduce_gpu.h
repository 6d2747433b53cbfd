#pragma once
// ICP on a Vulkan compute device (issue #40): the frame's pyramid (build_frame: depth_smooth.comp,
// depth_downsample.comp, depth_surface.comp, build_frame_pyramid's steps) and the sums
// IcpTracker's accumulate makes of every sampled pixel's rows (icp_correspondence), made per
// image row by icp_reduce.comp and returned for the tracker to add in double, in row order. The
// tracker solves each 6x6 system on the CPU: per Gauss-Newton iteration one dispatch.
//
// Tolerance against the CPU: each row's float sums are added in a tree rather than pixel by pixel,
// and a driver may fuse multiply-adds, so a row's sums differ by float rounding (about 1e-6 of
// their size). A solve moves by far less than ICP's stopping step (IcpOptions::min_update_m),
// except where rounding picks another model pixel for a frame pixel on a pixel boundary; the
// runs then stop within a step of the same minimum each, which is what the tests allow
// (tests/core/test_gpu_tracking.cpp).

#include "depth_pyramid.h"
#include "icp_kernels.h"

#include <gpu/compute_device.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace roomprobe {

class IcpReducerGpu {
public:
	// Per sampled row: J^T J's upper triangle (21), J^T r (6), the traces of the rotation and
	// translation blocks of the point-to-plane rows, their sum of squared residuals, the inliers, 0.
	static constexpr int ROW_FLOATS = 32;
	// Per sampled pixel of the frame: vertex, normal, intensity, flags (icp_reduce.comp's Frame).
	static constexpr int FRAME_FLOATS = 8;

	// Null, with r_error, when the kernel cannot be made on p_device.
	static std::unique_ptr<IcpReducerGpu> create(std::shared_ptr<ComputeDevice> p_device, std::string *r_error);

	// One tracking call at a time goes through the buffers: hold this lock from build_frame (or
	// set_frame) to the last reduce.
	std::mutex &mutex() const { return busy; }
	// The frame's first p_levels levels; level 0 only every p_finest_stride-th pixel of every
	// p_finest_stride-th row, as the CPU pairs it.
	bool set_frame(const FramePyramid &p_frame, int p_levels, int p_finest_stride, std::string *r_error);
	// The same levels made on the device from the frame itself, as build_frame_pyramid makes
	// them: p_clean_depth_m (clean_depth's) and, for the colour term, p_rgb (CV_8UC3; may be empty).
	// Differs from set_frame's by float rounding (a driver may fuse multiply-adds), and so by a
	// normal or two whose depth step sits on max_jump_relative.
	bool build_frame(const cv::Mat &p_clean_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, int p_levels, float p_band_m,
			const SurfaceOptions &p_surface, int p_finest_stride, std::string *r_error);
	// The frame as icp_reduce.comp reads it (8 floats per sampled pixel, level after level).
	std::vector<float> frame_floats() const;
	// The reference, with its intensity and gradients when p_model has them (else geometry only).
	bool set_model(const IcpModelView &p_model, std::string *r_error);
	// The rows of level p_level at p_params (colour rows when p_params.colour_weight is not 0 and
	// the model has intensity): r_rows points at *r_row_count rows of ROW_FLOATS, valid until
	// the next call.
	bool reduce(int p_level, const IcpKernelParams &p_params, const float **r_rows, int *r_row_count, std::string *r_error);

	// After a failed dispatch the reducer is not used again (its device may be lost): why.
	void set_failed(const std::string &p_reason);
	bool has_failed() const { return failed.load(); }
	std::string failure() const;

private:
	IcpReducerGpu() = default;
	bool ensure(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error) const;
	// Sizes levels for p_levels levels of p_camera (level 0 sampled every p_finest_stride-th
	// pixel); the frame's floats.
	size_t plan_levels(const PinholeIntrinsics &p_camera, int p_levels, int p_finest_stride);
	bool make_pyramid_kernels(std::string *r_error);

	struct Level {
		int cols = 0, rows = 0; // sampled
		size_t first_float = 0; // in the frame buffer
	};
	std::shared_ptr<ComputeDevice> compute; // outlives the buffers below
	std::unique_ptr<GpuKernel> kernel;
	std::unique_ptr<GpuBuffer> params, frame, model, rows;
	// build_frame's: made at its first call.
	std::unique_ptr<GpuKernel> smooth_kernel, downsample_kernel, surface_kernel;
	std::unique_ptr<GpuBuffer> depth, intensity, weights;
	int weights_radius = -1; // the radius the weights buffer holds
	std::vector<Level> levels;
	bool model_colour = false;
	// The model's camera and pose, for the parameters.
	PinholeIntrinsics model_camera;
	glm::mat3 model_rotation = glm::mat3(1.0f);
	glm::vec3 model_translation = glm::vec3(0.0f);
	mutable std::mutex busy;
	std::atomic<bool> failed{ false };
	std::string failure_reason;
	mutable std::mutex failure_mutex;
};

} // namespace roomprobe
