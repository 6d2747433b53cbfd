#include "ggx_prefilter_gpu.h"

#include <spirv/ggx_prefilter.h>

#include <algorithm>
#include <cstring>

namespace roomprobe {

namespace {

constexpr uint32_t GROUP_SIZE = 64; // ggx_prefilter.comp's local_size_x

template <typename T>
std::unique_ptr<GpuBuffer> upload(const ComputeDevice &p_device, const std::vector<T> &p_values, std::string *r_error) {
	std::unique_ptr<GpuBuffer> buffer = p_device.make_buffer(p_values.size() * sizeof(T), GpuAccess::DeviceReads, r_error);
	if (buffer && !p_values.empty()) {
		std::memcpy(buffer->data(), p_values.data(), p_values.size() * sizeof(T));
	}
	return buffer;
}

} // namespace

std::unique_ptr<GgxFilterGpu> GgxFilterGpu::create(std::shared_ptr<const GgxFilter> p_filter, std::shared_ptr<ComputeDevice> p_device, std::string *r_error) {
	if (!p_filter || !p_filter->is_valid() || !p_device) {
		*r_error = "no GGX filter or no compute device";
		return nullptr;
	}
	std::unique_ptr<GgxFilterGpu> out(new GgxFilterGpu());
	out->compute = std::move(p_device);
	out->filter = std::move(p_filter);
	const ComputeDevice &device = *out->compute;
	// The device's limits: a level's workgroups, and each storage buffer's range.
	const VkPhysicalDeviceLimits &limits = device.limits();
	for (const GgxFilter::Level &level : out->filter->levels) {
		const uint64_t groups = (uint64_t(level.first.size() - 1) + GROUP_SIZE - 1) / GROUP_SIZE;
		const uint64_t largest = std::max<uint64_t>(level.texel.size() * sizeof(uint32_t), uint64_t(level.first.size() - 1) * 3 * sizeof(float));
		if (groups > limits.maxComputeWorkGroupCount[0] || largest > limits.maxStorageBufferRange ||
				out->filter->pyramid_texels() * 3 * sizeof(float) > limits.maxStorageBufferRange) {
			*r_error = "a " + std::to_string(out->filter->face_size()) + "^2 GGX filter exceeds the Vulkan device's limits (" + std::to_string(groups) +
					" workgroups, " + std::to_string(largest) + "-byte buffers)";
			return nullptr;
		}
	}
	out->kernel = device.make_kernel(spirv::ggx_prefilter, sizeof(spirv::ggx_prefilter) / sizeof(uint32_t), 5, sizeof(uint32_t), r_error, "ggx_prefilter");
	out->pyramid = device.make_buffer(out->filter->pyramid_texels() * 3 * sizeof(float), GpuAccess::DeviceReads, r_error);
	if (!out->kernel || !out->pyramid) {
		return nullptr;
	}
	for (int f = 0; f < 6; f++) {
		out->reads[size_t(f)] = uint8_t(1u << f); // level 0 is the source face itself
	}
	for (const GgxFilter::Level &level : out->filter->levels) {
		const size_t face_texels = size_t(level.size) * size_t(level.size);
		for (size_t t = 0; t < level.source_faces.size(); t++) {
			out->reads[t / face_texels] |= level.source_faces[t];
		}
		Level gpu;
		gpu.size = level.size;
		gpu.texels = uint32_t(level.first.size() - 1);
		gpu.first = upload(device, level.first, r_error);
		gpu.texel = upload(device, level.texel, r_error);
		gpu.weight = upload(device, level.weight, r_error);
		gpu.result = device.make_buffer(size_t(gpu.texels) * 3 * sizeof(float), GpuAccess::HostReads, r_error);
		if (!gpu.first || !gpu.texel || !gpu.weight || !gpu.result) {
			return nullptr;
		}
		out->levels.push_back(std::move(gpu));
	}
	return out;
}

uint8_t GgxFilterGpu::dependent_faces(uint8_t p_changed_faces) const {
	uint8_t out = 0;
	for (size_t f = 0; f < 6; f++) {
		out |= (reads[f] & p_changed_faces) ? uint8_t(1u << f) : uint8_t(0);
	}
	return out;
}

std::vector<Cubemap> GgxFilterGpu::apply(const Cubemap &p_source, std::string *r_error) const {
	std::vector<Cubemap> chain;
	if (!is_valid_cubemap(p_source) || p_source.size != filter->face_size()) {
		*r_error = "the source is not a cubemap of the filter's face size";
		return chain;
	}
	const std::lock_guard<std::mutex> lock(mutex);
	const std::vector<cv::Vec3f> flat = filter->box_pyramid(p_source);
	std::memcpy(pyramid->data(), flat.data(), flat.size() * sizeof(cv::Vec3f));
	std::vector<GpuDispatch> dispatches;
	for (const Level &level : levels) {
		GpuDispatch dispatch;
		dispatch.kernel = kernel.get();
		dispatch.buffers = { pyramid.get(), level.first.get(), level.texel.get(), level.weight.get(), level.result.get() };
		dispatch.set_push(level.texels);
		dispatch.groups_x = (level.texels + GROUP_SIZE - 1) / GROUP_SIZE;
		dispatches.push_back(std::move(dispatch));
	}
	*r_error = compute->run(dispatches);
	if (!r_error->empty()) {
		return chain;
	}
	chain.push_back(p_source); // level 0: the source itself, its pixels shared
	for (const Level &level : levels) {
		Cubemap out = make_cubemap(level.size);
		const size_t face_floats = size_t(level.size) * size_t(level.size) * 3;
		for (size_t f = 0; f < 6; f++) {
			// make_cubemap's faces are continuous: one copy a face.
			std::memcpy(out.faces[f].ptr<float>(0), static_cast<const float *>(level.result->data()) + f * face_floats, face_floats * sizeof(float));
		}
		chain.push_back(std::move(out));
	}
	return chain;
}

} // namespace roomprobe
