#include "compute_device.h"

#include <algorithm>
#include <chrono>
#include <map>

namespace roomprobe {

namespace {

// Descriptor sets one batch may use: a batch's dispatches each take one.
constexpr uint32_t MAX_SETS = 64;
constexpr uint32_t MAX_BUFFERS_PER_SET = 8;

// A Vulkan info struct, zeroed, with its type set.
template <typename T>
T vk_struct(VkStructureType p_type) {
	T value{};
	value.sType = p_type;
	return value;
}

std::string failed(const char *p_call, VkResult p_result) {
	return std::string(p_call) + " failed: " + vk::result_name(p_result);
}

// GPUs first (discrete, integrated, virtual), CPU devices (lavapipe) last.
int device_rank(VkPhysicalDeviceType p_type) {
	switch (p_type) {
		case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
			return 0;
		case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
			return 1;
		case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
			return 2;
		case VK_PHYSICAL_DEVICE_TYPE_CPU:
			return 4;
		default:
			return 3;
	}
}

} // namespace

const char *compute_backend_name(ComputeBackend p_backend) {
	switch (p_backend) {
		case ComputeBackend::Cpu:
			return "cpu";
		case ComputeBackend::Vulkan:
			return "vulkan";
		case ComputeBackend::Auto:
			return "auto";
	}
	return "?";
}

bool compute_backend_from_name(const std::string &p_name, ComputeBackend *r_backend) {
	for (const ComputeBackend backend : { ComputeBackend::Cpu, ComputeBackend::Vulkan, ComputeBackend::Auto }) {
		if (p_name == compute_backend_name(backend)) {
			*r_backend = backend;
			return true;
		}
	}
	return false;
}

std::string compute_backend_note(ComputeBackend p_asked, const ComputeDevice *p_device, const std::string &p_why_not) {
	if (p_device != nullptr) {
		return "Vulkan: " + p_device->name();
	}
	return p_asked == ComputeBackend::Cpu ? std::string("CPU") : std::string("CPU (") + compute_backend_name(p_asked) + ": " + p_why_not + ")";
}

GpuBuffer::~GpuBuffer() {
	const vk::Api &api = device->api();
	if (device->is_lost()) {
		api.DeviceWaitIdle(device->handle()); // a batch that did not finish may still use it
	}
	if (mapped != nullptr) {
		api.UnmapMemory(device->handle(), memory);
		(device_local ? device->device_bytes : device->host_bytes) -= bytes;
	}
	api.DestroyBuffer(device->handle(), buffer, nullptr);
	api.FreeMemory(device->handle(), memory, nullptr);
}

GpuKernel::~GpuKernel() {
	const vk::Api &api = device->api();
	api.DestroyPipeline(device->handle(), pipeline, nullptr);
	api.DestroyPipelineLayout(device->handle(), layout, nullptr);
	api.DestroyDescriptorSetLayout(device->handle(), set_layout, nullptr);
	api.DestroyShaderModule(device->handle(), module, nullptr);
}

std::shared_ptr<ComputeDevice> ComputeDevice::create(const ComputeDeviceOptions &p_options, std::string *r_error) {
	std::shared_ptr<ComputeDevice> made(new ComputeDevice());
	*r_error = made->open(p_options);
	return r_error->empty() ? made : nullptr;
}

std::string ComputeDevice::open(const ComputeDeviceOptions &p_options) {
	std::string error;
	if (!vk::load_loader(&vk_api, &error)) {
		return error;
	}
	VkApplicationInfo app = vk_struct<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
	app.pApplicationName = "RoomProbe";
	app.apiVersion = VK_API_VERSION_1_1;
	VkInstanceCreateInfo instance_info = vk_struct<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
	instance_info.pApplicationInfo = &app;
	VkResult result = vk_api.CreateInstance(&instance_info, nullptr, &instance);
	if (result != VK_SUCCESS) {
		instance = VK_NULL_HANDLE;
		return failed("vkCreateInstance", result);
	}
	if (!vk::load_instance(instance, &vk_api, &error)) {
		return error;
	}
	uint32_t count = 0;
	vk_api.EnumeratePhysicalDevices(instance, &count, nullptr);
	std::vector<VkPhysicalDevice> devices(count);
	vk_api.EnumeratePhysicalDevices(instance, &count, devices.data());
	const std::vector<Candidate> candidates = rank_devices(devices, p_options);
	if (candidates.empty()) {
		return count == 0 ? std::string("no Vulkan device (the loader lists none)")
						  : std::string("no Vulkan device with a compute queue") + (p_options.allow_cpu_device ? "" : " that is not a CPU device");
	}
	// Best first; a device whose driver refuses (a broken install, an exhausted GPU) gives way to
	// the next, and the reasons of all that refused are kept.
	std::string refusals;
	for (const Candidate &candidate : candidates) {
		const std::string problem = open_device(candidate);
		if (problem.empty()) {
			return std::string();
		}
		close_device();
		refusals += (refusals.empty() ? "" : "; ") + candidate.name + ": " + problem;
	}
	return "no Vulkan device could be opened (" + refusals + ")";
}

std::vector<ComputeDevice::Candidate> ComputeDevice::rank_devices(const std::vector<VkPhysicalDevice> &p_devices, const ComputeDeviceOptions &p_options) const {
	std::vector<Candidate> candidates;
	for (VkPhysicalDevice physical_device : p_devices) {
		VkPhysicalDeviceProperties properties;
		vk_api.GetPhysicalDeviceProperties(physical_device, &properties);
		if (properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU && !p_options.allow_cpu_device) {
			continue;
		}
		uint32_t families = 0;
		vk_api.GetPhysicalDeviceQueueFamilyProperties(physical_device, &families, nullptr);
		std::vector<VkQueueFamilyProperties> family_properties(families);
		vk_api.GetPhysicalDeviceQueueFamilyProperties(physical_device, &families, family_properties.data());
		for (uint32_t f = 0; f < families; f++) {
			if (family_properties[f].queueFlags & VK_QUEUE_COMPUTE_BIT) {
				Candidate candidate;
				candidate.physical = physical_device;
				candidate.family = f;
				candidate.rank = device_rank(properties.deviceType);
				candidate.properties = properties;
				candidate.name = properties.deviceName;
				candidate.timestamp_bits = family_properties[f].timestampValidBits;
				candidates.push_back(candidate);
				break;
			}
		}
	}
	std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate &p_a, const Candidate &p_b) { return p_a.rank < p_b.rank; });
	return candidates;
}

std::string ComputeDevice::open_device(const Candidate &p_candidate) {
	physical = p_candidate.physical;
	device_name = p_candidate.name;
	device_limits = p_candidate.properties.limits;
	cpu = p_candidate.properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
	vk_api.GetPhysicalDeviceMemoryProperties(physical, &memory);
	if (memory_type(~0u) < 0) {
		return "no host-visible, coherent memory";
	}
	std::string error;
	const float priority = 1.0f;
	VkDeviceQueueCreateInfo queue_info = vk_struct<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
	queue_info.queueFamilyIndex = p_candidate.family;
	queue_info.queueCount = 1;
	queue_info.pQueuePriorities = &priority;
	VkDeviceCreateInfo device_info = vk_struct<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
	device_info.queueCreateInfoCount = 1;
	device_info.pQueueCreateInfos = &queue_info;
	VkResult result = vk_api.CreateDevice(physical, &device_info, nullptr, &device);
	if (result != VK_SUCCESS) {
		device = VK_NULL_HANDLE;
		return failed("vkCreateDevice", result);
	}
	if (!vk::load_device(device, &vk_api, &error)) {
		return error;
	}
	vk_api.GetDeviceQueue(device, p_candidate.family, 0, &queue);
	VkCommandPoolCreateInfo pool_info = vk_struct<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
	pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
	pool_info.queueFamilyIndex = p_candidate.family;
	if ((result = vk_api.CreateCommandPool(device, &pool_info, nullptr, &pool)) != VK_SUCCESS) {
		return failed("vkCreateCommandPool", result);
	}
	VkCommandBufferAllocateInfo command_info = vk_struct<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
	command_info.commandPool = pool;
	command_info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
	command_info.commandBufferCount = 1;
	if ((result = vk_api.AllocateCommandBuffers(device, &command_info, &commands)) != VK_SUCCESS) {
		return failed("vkAllocateCommandBuffers", result);
	}
	VkFenceCreateInfo fence_info = vk_struct<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
	if ((result = vk_api.CreateFence(device, &fence_info, nullptr, &fence)) != VK_SUCCESS) {
		return failed("vkCreateFence", result);
	}
	const VkDescriptorPoolSize sizes{ VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, MAX_SETS * MAX_BUFFERS_PER_SET };
	VkDescriptorPoolCreateInfo descriptor_info = vk_struct<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
	descriptor_info.maxSets = MAX_SETS;
	descriptor_info.poolSizeCount = 1;
	descriptor_info.pPoolSizes = &sizes;
	if ((result = vk_api.CreateDescriptorPool(device, &descriptor_info, nullptr, &descriptors)) != VK_SUCCESS) {
		return failed("vkCreateDescriptorPool", result);
	}
	if (p_candidate.timestamp_bits > 0 && device_limits.timestampPeriod > 0.0f) { // without them, batches are timed on the host alone
		VkQueryPoolCreateInfo query_info = vk_struct<VkQueryPoolCreateInfo>(VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO);
		query_info.queryType = VK_QUERY_TYPE_TIMESTAMP;
		query_info.queryCount = 2;
		if (vk_api.CreateQueryPool(device, &query_info, nullptr, &timestamps) != VK_SUCCESS) {
			timestamps = VK_NULL_HANDLE;
		}
		timestamp_mask = p_candidate.timestamp_bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << p_candidate.timestamp_bits) - 1;
	}
	return std::string();
}

void ComputeDevice::close_device() {
	// A device whose functions did not all load is only destroyed (open_device failed part way).
	if (device != VK_NULL_HANDLE && vk_api.DestroyDevice != nullptr && vk_api.QueueSubmit != nullptr) {
		vk_api.DeviceWaitIdle(device);
		vk_api.DestroyDescriptorPool(device, descriptors, nullptr);
		if (timestamps != VK_NULL_HANDLE) {
			vk_api.DestroyQueryPool(device, timestamps, nullptr);
		}
		vk_api.DestroyFence(device, fence, nullptr);
		vk_api.DestroyCommandPool(device, pool, nullptr);
		vk_api.DestroyDevice(device, nullptr);
	} else if (device != VK_NULL_HANDLE && vk_api.DestroyDevice != nullptr) {
		vk_api.DestroyDevice(device, nullptr);
	}
	device = VK_NULL_HANDLE;
	descriptors = VK_NULL_HANDLE;
	timestamps = VK_NULL_HANDLE;
	fence = VK_NULL_HANDLE;
	pool = VK_NULL_HANDLE;
	commands = VK_NULL_HANDLE;
	queue = VK_NULL_HANDLE;
	physical = VK_NULL_HANDLE;
}

ComputeDevice::~ComputeDevice() {
	close_device();
	if (instance != VK_NULL_HANDLE && vk_api.DestroyInstance != nullptr) {
		vk_api.DestroyInstance(instance, nullptr);
	}
}

int ComputeDevice::memory_type(uint32_t p_bits, VkMemoryPropertyFlags p_also, VkMemoryPropertyFlags p_avoid) const {
	const VkMemoryPropertyFlags wanted = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
	// With p_also and without p_avoid first, then with p_also, then without p_avoid, then any.
	const std::pair<VkMemoryPropertyFlags, VkMemoryPropertyFlags> tries[] = { { wanted | p_also, p_avoid }, { wanted | p_also, 0 }, { wanted, p_avoid }, { wanted, 0 } };
	for (const auto &[flags, avoid] : tries) {
		for (uint32_t i = 0; i < memory.memoryTypeCount; i++) {
			const VkMemoryPropertyFlags has = memory.memoryTypes[i].propertyFlags;
			if ((p_bits & (1u << i)) && (has & flags) == flags && (has & avoid) == 0) {
				return int(i);
			}
		}
	}
	return -1;
}

std::string ComputeDevice::bind_memory(GpuBuffer *r_buffer, VkMemoryRequirements p_needs, int p_type) const {
	VkMemoryAllocateInfo allocate = vk_struct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
	allocate.allocationSize = p_needs.size;
	allocate.memoryTypeIndex = uint32_t(p_type);
	VkResult result = vk_api.AllocateMemory(device, &allocate, nullptr, &r_buffer->memory);
	if (result != VK_SUCCESS) {
		r_buffer->memory = VK_NULL_HANDLE;
		return failed("vkAllocateMemory", result) + " (" + std::to_string(p_needs.size) + " bytes)";
	}
	if ((result = vk_api.BindBufferMemory(device, r_buffer->buffer, r_buffer->memory, 0)) != VK_SUCCESS) {
		vk_api.FreeMemory(device, r_buffer->memory, nullptr); // not bound: another type may still be tried
		r_buffer->memory = VK_NULL_HANDLE;
		return failed("vkBindBufferMemory", result);
	}
	if ((result = vk_api.MapMemory(device, r_buffer->memory, 0, VK_WHOLE_SIZE, 0, &r_buffer->mapped)) != VK_SUCCESS) {
		r_buffer->mapped = nullptr;
		return failed("vkMapMemory", result);
	}
	r_buffer->device_local = (memory.memoryTypes[p_type].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) != 0;
	(r_buffer->device_local ? device_bytes : host_bytes) += r_buffer->bytes;
	return std::string();
}

std::unique_ptr<GpuBuffer> ComputeDevice::make_buffer(size_t p_bytes, GpuAccess p_access, std::string *r_error) const {
	std::unique_ptr<GpuBuffer> out(new GpuBuffer());
	out->device = this;
	out->bytes = p_bytes;
	VkBufferCreateInfo info = vk_struct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
	info.size = std::max<size_t>(p_bytes, 4); // a zero-sized buffer is invalid
	info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
	info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
	const VkResult result = vk_api.CreateBuffer(device, &info, nullptr, &out->buffer);
	if (result != VK_SUCCESS) {
		*r_error = failed("vkCreateBuffer", result);
		return nullptr;
	}
	VkMemoryRequirements needs;
	vk_api.GetBufferMemoryRequirements(device, out->buffer, &needs);
	// What the device reads: its own memory where the host can map it. What the host reads: cached,
	// and not a discrete GPU's write-combined BAR.
	const bool device_reads = p_access == GpuAccess::DeviceReads;
	const int type = device_reads ? memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
								  : memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_CACHED_BIT, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
	if (type < 0) {
		*r_error = "the Vulkan device has no host-visible, coherent memory for a storage buffer";
		return nullptr;
	}
	std::string problem = bind_memory(out.get(), needs, type);
	// A discrete GPU's mappable device memory may be a small heap (a 256-MiB BAR): host memory then
	// (where the memory was not bound: a buffer is bound once).
	if (!problem.empty() && out->memory == VK_NULL_HANDLE && device_reads) {
		const int host_type = memory_type(needs.memoryTypeBits & ~(1u << uint32_t(type)), 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
		if (host_type >= 0 && !(memory.memoryTypes[host_type].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)) {
			problem = bind_memory(out.get(), needs, host_type);
		}
	}
	if (!problem.empty()) {
		*r_error = problem;
		return nullptr;
	}
	return out;
}

bool ComputeDevice::ensure_buffer(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error, size_t p_slack_bytes) const {
	if (*r_buffer && (*r_buffer)->size_bytes() >= p_bytes) {
		return true;
	}
	r_buffer->reset(); // before the new one: the old one's memory may be needed
	*r_buffer = make_buffer(p_bytes + p_slack_bytes, p_access, r_error);
	return bool(*r_buffer);
}

std::unique_ptr<GpuKernel> ComputeDevice::make_kernel(const uint32_t *p_spirv, size_t p_words, int p_buffers, uint32_t p_push_bytes, std::string *r_error,
		const char *p_label) const {
	std::unique_ptr<GpuKernel> out(new GpuKernel());
	out->device = this;
	out->name = p_label;
	out->buffers = p_buffers;
	out->push_bytes = p_push_bytes;
	VkShaderModuleCreateInfo module_info = vk_struct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
	module_info.codeSize = p_words * sizeof(uint32_t);
	module_info.pCode = p_spirv;
	VkResult result = vk_api.CreateShaderModule(device, &module_info, nullptr, &out->module);
	if (result != VK_SUCCESS) {
		*r_error = failed("vkCreateShaderModule", result);
		return nullptr;
	}
	std::vector<VkDescriptorSetLayoutBinding> bindings(static_cast<size_t>(p_buffers));
	for (int b = 0; b < p_buffers; b++) {
		bindings[size_t(b)] = { uint32_t(b), VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr };
	}
	VkDescriptorSetLayoutCreateInfo set_info = vk_struct<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
	set_info.bindingCount = uint32_t(p_buffers);
	set_info.pBindings = bindings.data();
	if ((result = vk_api.CreateDescriptorSetLayout(device, &set_info, nullptr, &out->set_layout)) != VK_SUCCESS) {
		*r_error = failed("vkCreateDescriptorSetLayout", result);
		return nullptr;
	}
	const VkPushConstantRange push{ VK_SHADER_STAGE_COMPUTE_BIT, 0, p_push_bytes };
	VkPipelineLayoutCreateInfo layout_info = vk_struct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
	layout_info.setLayoutCount = 1;
	layout_info.pSetLayouts = &out->set_layout;
	layout_info.pushConstantRangeCount = p_push_bytes > 0 ? 1 : 0;
	layout_info.pPushConstantRanges = &push;
	if ((result = vk_api.CreatePipelineLayout(device, &layout_info, nullptr, &out->layout)) != VK_SUCCESS) {
		*r_error = failed("vkCreatePipelineLayout", result);
		return nullptr;
	}
	VkComputePipelineCreateInfo pipeline_info = vk_struct<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
	pipeline_info.stage = { VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_COMPUTE_BIT, out->module, "main", nullptr };
	pipeline_info.layout = out->layout;
	if ((result = vk_api.CreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &out->pipeline)) != VK_SUCCESS) {
		*r_error = failed("vkCreateComputePipelines", result);
		return nullptr;
	}
	return out;
}

std::string ComputeDevice::run(const std::vector<GpuDispatch> &p_dispatches) const {
	if (p_dispatches.size() > MAX_SETS) {
		return "a batch of " + std::to_string(p_dispatches.size()) + " dispatches (at most " + std::to_string(MAX_SETS) + ")";
	}
	const std::lock_guard<std::mutex> lock(queue_mutex);
	if (lost) {
		return "the Vulkan device was lost (an earlier batch did not finish)";
	}
	VkResult reset = vk_api.ResetDescriptorPool(device, descriptors, 0);
	if (reset == VK_SUCCESS) {
		reset = vk_api.ResetCommandBuffer(commands, 0);
	}
	if (reset != VK_SUCCESS) {
		return failed("resetting the command buffer", reset);
	}
	VkCommandBufferBeginInfo begin = vk_struct<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
	begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
	const auto wall_start = std::chrono::steady_clock::now();
	if ((reset = vk_api.BeginCommandBuffer(commands, &begin)) != VK_SUCCESS) {
		return failed("vkBeginCommandBuffer", reset);
	}
	if (timestamps != VK_NULL_HANDLE) {
		vk_api.CmdResetQueryPool(commands, timestamps, 0, 2);
		vk_api.CmdWriteTimestamp(commands, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, timestamps, 0);
	}
	for (size_t d = 0; d < p_dispatches.size(); d++) {
		const GpuDispatch &dispatch = p_dispatches[d];
		const GpuKernel &kernel = *dispatch.kernel;
		if (int(dispatch.buffers.size()) != kernel.buffers || dispatch.push.size() != kernel.push_bytes) {
			vk_api.EndCommandBuffer(commands);
			return "dispatch " + std::to_string(d) + ": its buffers or push constants do not match the kernel's";
		}
		VkDescriptorSetAllocateInfo allocate = vk_struct<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
		allocate.descriptorPool = descriptors;
		allocate.descriptorSetCount = 1;
		allocate.pSetLayouts = &kernel.set_layout;
		VkDescriptorSet set = VK_NULL_HANDLE;
		const VkResult result = vk_api.AllocateDescriptorSets(device, &allocate, &set);
		if (result != VK_SUCCESS) {
			vk_api.EndCommandBuffer(commands);
			return failed("vkAllocateDescriptorSets", result);
		}
		std::vector<VkDescriptorBufferInfo> infos(dispatch.buffers.size());
		std::vector<VkWriteDescriptorSet> writes(dispatch.buffers.size());
		for (size_t b = 0; b < dispatch.buffers.size(); b++) {
			const GpuWindow window = b < dispatch.windows.size() ? dispatch.windows[b] : GpuWindow();
			infos[b] = { dispatch.buffers[b]->buffer, window.offset, window.bytes > 0 ? window.bytes : VK_WHOLE_SIZE };
			writes[b] = { VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, set, uint32_t(b), 0, 1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, nullptr, &infos[b], nullptr };
		}
		vk_api.UpdateDescriptorSets(device, uint32_t(writes.size()), writes.data(), 0, nullptr);
		if (d > 0) {
			// Each dispatch sees what the ones before it wrote.
			VkMemoryBarrier barrier = vk_struct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
			barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
			barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
			vk_api.CmdPipelineBarrier(commands, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
		}
		vk_api.CmdBindPipeline(commands, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.pipeline);
		vk_api.CmdBindDescriptorSets(commands, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.layout, 0, 1, &set, 0, nullptr);
		if (kernel.push_bytes > 0) {
			vk_api.CmdPushConstants(commands, kernel.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, kernel.push_bytes, dispatch.push.data());
		}
		vk_api.CmdDispatch(commands, dispatch.groups_x, dispatch.groups_y, dispatch.groups_z);
	}
	// The host reads the results after the fence.
	VkMemoryBarrier to_host = vk_struct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
	to_host.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
	to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
	vk_api.CmdPipelineBarrier(commands, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, nullptr, 0, nullptr);
	if (timestamps != VK_NULL_HANDLE) {
		vk_api.CmdWriteTimestamp(commands, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, timestamps, 1);
	}
	if ((reset = vk_api.EndCommandBuffer(commands)) != VK_SUCCESS) {
		return failed("vkEndCommandBuffer", reset);
	}
	VkSubmitInfo submit = vk_struct<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
	submit.commandBufferCount = 1;
	submit.pCommandBuffers = &commands;
	vk_api.ResetFences(device, 1, &fence);
	VkResult result = vk_api.QueueSubmit(queue, 1, &submit, fence);
	if (result != VK_SUCCESS) {
		return failed("vkQueueSubmit", result);
	}
	constexpr uint64_t TIMEOUT_NS = 10'000'000'000ull; // a hung device is an error, not a hang
	result = vk_api.WaitForFences(device, 1, &fence, VK_TRUE, TIMEOUT_NS);
	if (result != VK_SUCCESS) {
		lost = true; // the batch may still run: nothing it uses may be reset or freed by a next one
		return failed("vkWaitForFences", result);
	}
	record_batch(p_dispatches, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_start).count());
	return std::string();
}

void ComputeDevice::record_batch(const std::vector<GpuDispatch> &p_dispatches, double p_wall_ms) const {
	std::string kind;
	for (const GpuDispatch &dispatch : p_dispatches) {
		const std::string &label = dispatch.kernel->label();
		if (kind != label && !kind.ends_with("+" + label)) { // a kernel dispatched again in a row is named once
			kind += (kind.empty() ? "" : "+") + label;
		}
	}
	GpuBatchStats &stats = batches[kind];
	stats.kind = kind;
	stats.batches++;
	stats.wall_ms += p_wall_ms;
	uint64_t ticks[2] = { 0, 0 };
	if (timestamps != VK_NULL_HANDLE &&
			vk_api.GetQueryPoolResults(device, timestamps, 0, 2, sizeof(ticks), ticks, sizeof(uint64_t), VK_QUERY_RESULT_64_BIT) == VK_SUCCESS) {
		stats.device_ms += double((ticks[1] - ticks[0]) & timestamp_mask) * double(device_limits.timestampPeriod) * 1e-6;
		stats.timed = true;
	}
}

std::vector<GpuBatchStats> ComputeDevice::batch_stats() const {
	const std::lock_guard<std::mutex> lock(queue_mutex);
	std::vector<GpuBatchStats> out;
	for (const auto &[kind, stats] : batches) {
		out.push_back(stats);
	}
	return out;
}

void ComputeDevice::reset_batch_stats() const {
	const std::lock_guard<std::mutex> lock(queue_mutex);
	batches.clear();
}

std::shared_ptr<ComputeDevice> shared_compute_device(ComputeBackend p_backend, std::string *r_reason) {
	r_reason->clear();
	if (p_backend == ComputeBackend::Cpu) {
		return nullptr;
	}
	static std::mutex mutex;
	// By allow_cpu_device. Never destroyed: at exit the driver may already be gone.
	static auto &made = *new std::map<bool, std::pair<std::shared_ptr<ComputeDevice>, std::string>>();
	const bool allow_cpu = p_backend == ComputeBackend::Vulkan;
	const std::lock_guard<std::mutex> lock(mutex);
	auto found = made.find(allow_cpu);
	if (found == made.end()) {
		ComputeDeviceOptions options;
		options.allow_cpu_device = allow_cpu;
		std::string error;
		std::shared_ptr<ComputeDevice> device = ComputeDevice::create(options, &error);
		found = made.emplace(allow_cpu, std::make_pair(device, error)).first;
	}
	*r_reason = found->second.second;
	return found->second.first;
}

} // namespace roomprobe
