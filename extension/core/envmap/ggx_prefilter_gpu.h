#pragma once
// The GGX prefilter on a Vulkan compute device (issue #40): GgxFilter's taps uploaded once, then a
// map's chain is the box pyramid (built on the CPU, as GgxFilter::apply builds it) uploaded and one
// gather dispatch per level (ggx_prefilter.comp). The same sums in the same order as the CPU's, in
// float: the tests hold the two to the float rounding of a texel's taps.

#include "ggx_prefilter.h"

#include <gpu/compute_device.h>

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace roomprobe {

class GgxFilterGpu {
public:
	// Null, with r_error saying why, when a buffer or the kernel cannot be made.
	static std::unique_ptr<GgxFilterGpu> create(std::shared_ptr<const GgxFilter> p_filter, std::shared_ptr<ComputeDevice> p_device, std::string *r_error);

	int face_size() const { return filter->face_size(); }
	const ComputeDevice &device() const { return *compute; }
	// The chain of p_source (level 0 shares its pixels), as GgxFilter::apply(p_source) gives it.
	// Empty, with r_error, when the device fails or p_source is not of face_size().
	std::vector<Cubemap> apply(const Cubemap &p_source, std::string *r_error) const;
	// The output faces (a bit each) some level of which reads a source face of p_changed_faces:
	// the others come out as they were, so a map need not convert or upload them again.
	uint8_t dependent_faces(uint8_t p_changed_faces) const;

private:
	GgxFilterGpu() = default;
	struct Level {
		int size = 0;
		uint32_t texels = 0;
		std::unique_ptr<GpuBuffer> first, texel, weight, result;
	};
	std::shared_ptr<ComputeDevice> compute; // outlives the buffers below
	std::shared_ptr<const GgxFilter> filter;
	std::unique_ptr<GpuKernel> kernel;
	std::unique_ptr<GpuBuffer> pyramid;
	std::vector<Level> levels;
	std::array<uint8_t, 6> reads{}; // per output face: the source faces its levels read
	mutable std::mutex mutex; // one map at a time through the pyramid and result buffers
};

} // namespace roomprobe
