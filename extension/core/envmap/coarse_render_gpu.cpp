#include "coarse_render_gpu.h"

#include <spirv/coarse_gather.h>

#include <cstring>

namespace roomprobe {

namespace {

constexpr uint32_t GROUP_SIZE = 64; // coarse_gather.comp's local_size_x
constexpr size_t TAPS_BYTES = 32; // CoarseCubemapRenderer::Taps (static_assert there)

struct GatherPush {
	uint32_t texels = 0;
	uint32_t channels = 0;
};

} // namespace

std::unique_ptr<CoarseGatherGpu> CoarseGatherGpu::create(std::shared_ptr<ComputeDevice> p_device, std::string *r_error) {
	if (!p_device) {
		*r_error = "no compute device";
		return nullptr;
	}
	std::unique_ptr<CoarseGatherGpu> out(new CoarseGatherGpu());
	out->compute = std::move(p_device);
	out->kernel = out->compute->make_kernel(spirv::coarse_gather, sizeof(spirv::coarse_gather) / sizeof(uint32_t), 3, sizeof(GatherPush), r_error, "coarse_gather");
	if (!out->kernel) {
		return nullptr;
	}
	return out;
}

bool CoarseGatherGpu::upload(Slot *io_slot, const std::shared_ptr<const void> &p_taps_owner, const void *p_taps, size_t p_texels, const cv::Mat &p_atlas,
		bool p_atlas_published, std::string *r_error) {
	const ComputeDevice &device = *compute;
	const size_t channels = size_t(p_atlas.channels());
	const size_t taps_bytes = p_texels * TAPS_BYTES, atlas_bytes = p_atlas.total() * channels * sizeof(float);
	const size_t faces_bytes = p_texels * channels * sizeof(float);
	const uint64_t range = device.limits().maxStorageBufferRange;
	if (taps_bytes > range || atlas_bytes > range || faces_bytes > range) {
		*r_error = "the coarse render's buffers (" + std::to_string(taps_bytes) + " bytes of taps, " + std::to_string(atlas_bytes) +
				" of atlas) exceed the Vulkan device's storage buffer range (" + std::to_string(range) + " bytes)";
		return false;
	}
	if (!device.ensure_buffer(&io_slot->taps, taps_bytes, GpuAccess::DeviceReads, r_error) ||
			!device.ensure_buffer(&io_slot->atlas_buffer, atlas_bytes, GpuAccess::DeviceReads, r_error) ||
			!device.ensure_buffer(&io_slot->faces, faces_bytes, GpuAccess::HostReads, r_error)) {
		io_slot->forget();
		return false;
	}
	if (io_slot->taps_owner != p_taps_owner) {
		std::memcpy(io_slot->taps->data(), p_taps, taps_bytes);
		io_slot->taps_owner = p_taps_owner;
	}
	// A published atlas is never written again, and holding it keeps its address from another.
	if (!(p_atlas_published && io_slot->atlas.data == p_atlas.data && io_slot->atlas.size == p_atlas.size)) {
		std::memcpy(io_slot->atlas_buffer->data(), p_atlas.ptr<float>(), atlas_bytes);
		io_slot->atlas = p_atlas_published ? p_atlas : cv::Mat();
	}
	return true;
}

bool CoarseGatherGpu::gather(const std::shared_ptr<const void> &p_taps_owner, const void *p_taps, int p_size, const cv::Mat &p_atlas, bool p_atlas_published,
		std::array<cv::Mat, 6> *r_faces, std::string *r_error) {
	const int channels = p_atlas.channels();
	if ((p_atlas.type() != CV_32FC1 && p_atlas.type() != CV_32FC3) || !p_atlas.isContinuous() || p_size < 1) {
		*r_error = "the coarse render takes a continuous CV_32FC1 or CV_32FC3 atlas";
		return false;
	}
	Slot &slot = slots[channels == 1 ? 0 : 1];
	const size_t face_texels = size_t(p_size) * size_t(p_size), texels = 6 * face_texels;
	const uint64_t groups = (uint64_t(texels) + GROUP_SIZE - 1) / GROUP_SIZE;
	if (groups > compute->limits().maxComputeWorkGroupCount[0]) {
		*r_error = "a " + std::to_string(p_size) + "^2 coarse render needs " + std::to_string(groups) + " workgroups, more than the Vulkan device's " +
				std::to_string(compute->limits().maxComputeWorkGroupCount[0]);
		return false;
	}
	if (!upload(&slot, p_taps_owner, p_taps, texels, p_atlas, p_atlas_published, r_error)) {
		return false;
	}
	GpuDispatch dispatch;
	dispatch.kernel = kernel.get();
	dispatch.buffers = { slot.taps.get(), slot.atlas_buffer.get(), slot.faces.get() };
	GatherPush push;
	push.texels = uint32_t(texels);
	push.channels = uint32_t(channels);
	dispatch.set_push(push);
	dispatch.groups_x = uint32_t(groups);
	*r_error = compute->run({ dispatch });
	if (!r_error->empty()) {
		slot.forget();
		return false;
	}
	const float *faces = static_cast<const float *>(slot.faces->data());
	for (size_t f = 0; f < 6; f++) {
		(*r_faces)[f].create(p_size, p_size, CV_MAKETYPE(CV_32F, channels));
		std::memcpy((*r_faces)[f].ptr<float>(), faces + f * face_texels * size_t(channels), face_texels * size_t(channels) * sizeof(float));
	}
	return true;
}

} // namespace roomprobe
