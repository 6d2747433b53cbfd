#pragma once
// The Vulkan functions the compute backend calls, loaded at run time from the system's loader
// (libvulkan.so.1, dlopen): RoomProbe links no Vulkan library, so the addon bundles none and runs
// where there is none (the CPU backend then). Godot itself brings the loader on every desktop.

#define VK_NO_PROTOTYPES
#include <vulkan/vulkan.h>

#include <string>

namespace roomprobe::vk {

// The global and instance-level functions, filled by load_instance; the device-level ones by
// load_device. Null until loaded.
struct Api {
	PFN_vkGetInstanceProcAddr GetInstanceProcAddr = nullptr;
	PFN_vkCreateInstance CreateInstance = nullptr;
	PFN_vkEnumerateInstanceVersion EnumerateInstanceVersion = nullptr;

	PFN_vkDestroyInstance DestroyInstance = nullptr;
	PFN_vkEnumeratePhysicalDevices EnumeratePhysicalDevices = nullptr;
	PFN_vkGetPhysicalDeviceProperties GetPhysicalDeviceProperties = nullptr;
	PFN_vkGetPhysicalDeviceQueueFamilyProperties GetPhysicalDeviceQueueFamilyProperties = nullptr;
	PFN_vkGetPhysicalDeviceMemoryProperties GetPhysicalDeviceMemoryProperties = nullptr;
	PFN_vkCreateDevice CreateDevice = nullptr;
	PFN_vkGetDeviceProcAddr GetDeviceProcAddr = nullptr;

	PFN_vkDestroyDevice DestroyDevice = nullptr;
	PFN_vkGetDeviceQueue GetDeviceQueue = nullptr;
	PFN_vkDeviceWaitIdle DeviceWaitIdle = nullptr;
	PFN_vkCreateBuffer CreateBuffer = nullptr;
	PFN_vkDestroyBuffer DestroyBuffer = nullptr;
	PFN_vkGetBufferMemoryRequirements GetBufferMemoryRequirements = nullptr;
	PFN_vkAllocateMemory AllocateMemory = nullptr;
	PFN_vkFreeMemory FreeMemory = nullptr;
	PFN_vkBindBufferMemory BindBufferMemory = nullptr;
	PFN_vkMapMemory MapMemory = nullptr;
	PFN_vkUnmapMemory UnmapMemory = nullptr;
	PFN_vkCreateShaderModule CreateShaderModule = nullptr;
	PFN_vkDestroyShaderModule DestroyShaderModule = nullptr;
	PFN_vkCreateDescriptorSetLayout CreateDescriptorSetLayout = nullptr;
	PFN_vkDestroyDescriptorSetLayout DestroyDescriptorSetLayout = nullptr;
	PFN_vkCreatePipelineLayout CreatePipelineLayout = nullptr;
	PFN_vkDestroyPipelineLayout DestroyPipelineLayout = nullptr;
	PFN_vkCreateComputePipelines CreateComputePipelines = nullptr;
	PFN_vkDestroyPipeline DestroyPipeline = nullptr;
	PFN_vkCreateDescriptorPool CreateDescriptorPool = nullptr;
	PFN_vkDestroyDescriptorPool DestroyDescriptorPool = nullptr;
	PFN_vkResetDescriptorPool ResetDescriptorPool = nullptr;
	PFN_vkAllocateDescriptorSets AllocateDescriptorSets = nullptr;
	PFN_vkUpdateDescriptorSets UpdateDescriptorSets = nullptr;
	PFN_vkCreateCommandPool CreateCommandPool = nullptr;
	PFN_vkDestroyCommandPool DestroyCommandPool = nullptr;
	PFN_vkAllocateCommandBuffers AllocateCommandBuffers = nullptr;
	PFN_vkResetCommandBuffer ResetCommandBuffer = nullptr;
	PFN_vkBeginCommandBuffer BeginCommandBuffer = nullptr;
	PFN_vkEndCommandBuffer EndCommandBuffer = nullptr;
	PFN_vkCmdBindPipeline CmdBindPipeline = nullptr;
	PFN_vkCmdBindDescriptorSets CmdBindDescriptorSets = nullptr;
	PFN_vkCmdPushConstants CmdPushConstants = nullptr;
	PFN_vkCmdDispatch CmdDispatch = nullptr;
	PFN_vkCmdPipelineBarrier CmdPipelineBarrier = nullptr;
	PFN_vkCreateFence CreateFence = nullptr;
	PFN_vkDestroyFence DestroyFence = nullptr;
	PFN_vkResetFences ResetFences = nullptr;
	PFN_vkWaitForFences WaitForFences = nullptr;
	PFN_vkQueueSubmit QueueSubmit = nullptr;
	PFN_vkCreateQueryPool CreateQueryPool = nullptr; // the batches' timestamps (ComputeDevice::batch_stats)
	PFN_vkDestroyQueryPool DestroyQueryPool = nullptr;
	PFN_vkCmdResetQueryPool CmdResetQueryPool = nullptr;
	PFN_vkCmdWriteTimestamp CmdWriteTimestamp = nullptr;
	PFN_vkGetQueryPoolResults GetQueryPoolResults = nullptr;
};

// Opens the loader and takes the global functions. False, with r_error naming the library and
// what failed, where there is no loader.
bool load_loader(Api *r_api, std::string *r_error);
// The instance-level functions of p_instance.
bool load_instance(VkInstance p_instance, Api *io_api, std::string *r_error);
// The device-level functions of p_device.
bool load_device(VkDevice p_device, Api *io_api, std::string *r_error);

// "VK_ERROR_OUT_OF_DEVICE_MEMORY" and the like, for messages.
const char *result_name(VkResult p_result);

} // namespace roomprobe::vk
