#pragma once
// SH projection (project_sh) on a Vulkan compute device (issue #40): the same faces (box-filtered
// to SH_PROJECTION_FACE_SIZE), the same y_i dOmega table uploaded once, each face row summed in
// float by one invocation (sh_project.comp), the rows added in double on the host in row order,
// as project_sh adds them.

#include "spherical_harmonics.h"

#include <gpu/compute_device.h>

#include <memory>
#include <mutex>
#include <string>

namespace roomprobe {

class ShProjectorGpu {
public:
	// For cubemaps whose projected faces are p_size (SH_PROJECTION_FACE_SIZE, or smaller maps'
	// own size). Null, with r_error, when a buffer or the kernel cannot be made.
	static std::unique_ptr<ShProjectorGpu> create(int p_size, std::shared_ptr<ComputeDevice> p_device, std::string *r_error);

	// project_sh(p_cubemap) on the device. False, with r_error, when the device fails or the
	// cubemap's projected faces are not of this projector's size.
	bool project(const Cubemap &p_cubemap, ShCoefficients *r_sh, std::string *r_error) const;

private:
	ShProjectorGpu() = default;
	std::shared_ptr<ComputeDevice> compute; // outlives the buffers below
	int size = 0;
	std::unique_ptr<GpuKernel> kernel;
	std::unique_ptr<GpuBuffer> faces, weights, rows;
	mutable std::mutex mutex; // one cubemap at a time through the buffers
};

} // namespace roomprobe
