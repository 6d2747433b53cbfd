#pragma once
// The coarse cubemap's gather (CoarseCubemapRenderer, coarse_render.h) on a Vulkan compute device
// (issue #40): the rays and taps stay the CPU's (made once per probe position and size, and
// cached there); the device holds the taps and the atlas, and gathers every texel of the six faces
// (coarse_gather.comp), equal to the CPU's to the bit. The taps are uploaded again only for
// another lookup, the atlas only when it is another buffer that its caller says is published
// (never written again: the engine's coarse snapshots), or on every gather otherwise.

#include <gpu/compute_device.h>

#include <opencv2/core.hpp>

#include <array>
#include <memory>
#include <string>

namespace roomprobe {

class CoarseGatherGpu {
public:
	// Null, with r_error, when the kernel cannot be made.
	static std::unique_ptr<CoarseGatherGpu> create(std::shared_ptr<ComputeDevice> p_device, std::string *r_error);

	// The six p_size^2 faces (CV_32FC1 or CV_32FC3, as p_atlas, made here) of the 32-byte taps at
	// p_taps (6 p_size^2 of them, owned by p_taps_owner: the same owner, the same taps) over
	// p_atlas (continuous). False, with r_error, when the device fails or a buffer is beyond its
	// limits: the caller gathers on the CPU.
	bool gather(const std::shared_ptr<const void> &p_taps_owner, const void *p_taps, int p_size, const cv::Mat &p_atlas, bool p_atlas_published,
			std::array<cv::Mat, 6> *r_faces, std::string *r_error);

private:
	CoarseGatherGpu() = default;
	// One per channel count: the colour atlas and the observed mask alternate in every map.
	struct Slot {
		std::shared_ptr<const void> taps_owner; // held: no other lookup can take its address
		cv::Mat atlas; // held, likewise; empty: none uploaded, or not published
		std::unique_ptr<GpuBuffer> taps, atlas_buffer, faces;

		// After a failure nothing on the device is trusted: both are uploaded again.
		void forget() {
			taps_owner.reset();
			atlas.release();
		}
	};
	bool upload(Slot *io_slot, const std::shared_ptr<const void> &p_taps_owner, const void *p_taps, size_t p_texels, const cv::Mat &p_atlas,
			bool p_atlas_published, std::string *r_error);

	std::shared_ptr<ComputeDevice> compute; // outlives the buffers
	std::unique_ptr<GpuKernel> kernel;
	std::array<Slot, 2> slots; // [0] one channel, [1] three
};

} // namespace roomprobe
