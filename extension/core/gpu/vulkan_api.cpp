#include "vulkan_api.h"

#include <dlfcn.h>

namespace roomprobe::vk {

namespace {

// The loader stays open for the process's life: its functions may be called until exit.
void *loader_library() {
	static void *const library = [] {
		void *handle = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
		return handle != nullptr ? handle : dlopen("libvulkan.so", RTLD_NOW | RTLD_LOCAL);
	}();
	return library;
}

template <typename T>
bool take(T *r_function, PFN_vkVoidFunction p_found, const char *p_name, std::string *r_error) {
	*r_function = reinterpret_cast<T>(p_found);
	if (*r_function == nullptr && r_error->empty()) {
		*r_error = std::string("the Vulkan loader has no ") + p_name;
	}
	return *r_function != nullptr;
}

} // namespace

bool load_loader(Api *r_api, std::string *r_error) {
	void *library = loader_library();
	if (library == nullptr) {
		const char *why = dlerror(); // once: a second call returns null
		*r_error = "no Vulkan loader (libvulkan.so.1 could not be opened: " + std::string(why != nullptr ? why : "not found") + ")";
		return false;
	}
	r_api->GetInstanceProcAddr = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(library, "vkGetInstanceProcAddr"));
	if (r_api->GetInstanceProcAddr == nullptr) {
		*r_error = "libvulkan.so.1 has no vkGetInstanceProcAddr";
		return false;
	}
	r_error->clear();
	const auto global = [&](const char *p_name) { return r_api->GetInstanceProcAddr(VK_NULL_HANDLE, p_name); };
	take(&r_api->CreateInstance, global("vkCreateInstance"), "vkCreateInstance", r_error);
	// Optional: a Vulkan 1.0 loader has none.
	r_api->EnumerateInstanceVersion = reinterpret_cast<PFN_vkEnumerateInstanceVersion>(global("vkEnumerateInstanceVersion"));
	return r_error->empty();
}

#define RP_VK_INSTANCE(name) take(&io_api->name, io_api->GetInstanceProcAddr(p_instance, "vk" #name), "vk" #name, r_error)
#define RP_VK_DEVICE(name) take(&io_api->name, io_api->GetDeviceProcAddr(p_device, "vk" #name), "vk" #name, r_error)

bool load_instance(VkInstance p_instance, Api *io_api, std::string *r_error) {
	r_error->clear();
	RP_VK_INSTANCE(DestroyInstance);
	RP_VK_INSTANCE(EnumeratePhysicalDevices);
	RP_VK_INSTANCE(GetPhysicalDeviceProperties);
	RP_VK_INSTANCE(GetPhysicalDeviceQueueFamilyProperties);
	RP_VK_INSTANCE(GetPhysicalDeviceMemoryProperties);
	RP_VK_INSTANCE(CreateDevice);
	RP_VK_INSTANCE(GetDeviceProcAddr);
	return r_error->empty();
}

bool load_device(VkDevice p_device, Api *io_api, std::string *r_error) {
	r_error->clear();
	RP_VK_DEVICE(DestroyDevice);
	RP_VK_DEVICE(GetDeviceQueue);
	RP_VK_DEVICE(DeviceWaitIdle);
	RP_VK_DEVICE(CreateBuffer);
	RP_VK_DEVICE(DestroyBuffer);
	RP_VK_DEVICE(GetBufferMemoryRequirements);
	RP_VK_DEVICE(AllocateMemory);
	RP_VK_DEVICE(FreeMemory);
	RP_VK_DEVICE(BindBufferMemory);
	RP_VK_DEVICE(MapMemory);
	RP_VK_DEVICE(UnmapMemory);
	RP_VK_DEVICE(CreateShaderModule);
	RP_VK_DEVICE(DestroyShaderModule);
	RP_VK_DEVICE(CreateDescriptorSetLayout);
	RP_VK_DEVICE(DestroyDescriptorSetLayout);
	RP_VK_DEVICE(CreatePipelineLayout);
	RP_VK_DEVICE(DestroyPipelineLayout);
	RP_VK_DEVICE(CreateComputePipelines);
	RP_VK_DEVICE(DestroyPipeline);
	RP_VK_DEVICE(CreateDescriptorPool);
	RP_VK_DEVICE(DestroyDescriptorPool);
	RP_VK_DEVICE(ResetDescriptorPool);
	RP_VK_DEVICE(AllocateDescriptorSets);
	RP_VK_DEVICE(UpdateDescriptorSets);
	RP_VK_DEVICE(CreateCommandPool);
	RP_VK_DEVICE(DestroyCommandPool);
	RP_VK_DEVICE(AllocateCommandBuffers);
	RP_VK_DEVICE(ResetCommandBuffer);
	RP_VK_DEVICE(BeginCommandBuffer);
	RP_VK_DEVICE(EndCommandBuffer);
	RP_VK_DEVICE(CmdBindPipeline);
	RP_VK_DEVICE(CmdBindDescriptorSets);
	RP_VK_DEVICE(CmdPushConstants);
	RP_VK_DEVICE(CmdDispatch);
	RP_VK_DEVICE(CmdPipelineBarrier);
	RP_VK_DEVICE(CreateFence);
	RP_VK_DEVICE(DestroyFence);
	RP_VK_DEVICE(ResetFences);
	RP_VK_DEVICE(WaitForFences);
	RP_VK_DEVICE(QueueSubmit);
	RP_VK_DEVICE(CreateQueryPool);
	RP_VK_DEVICE(DestroyQueryPool);
	RP_VK_DEVICE(CmdResetQueryPool);
	RP_VK_DEVICE(CmdWriteTimestamp);
	RP_VK_DEVICE(GetQueryPoolResults);
	return r_error->empty();
}

#undef RP_VK_INSTANCE
#undef RP_VK_DEVICE

const char *result_name(VkResult p_result) {
	switch (p_result) {
		case VK_SUCCESS:
			return "VK_SUCCESS";
		case VK_TIMEOUT:
			return "VK_TIMEOUT";
		case VK_ERROR_OUT_OF_HOST_MEMORY:
			return "VK_ERROR_OUT_OF_HOST_MEMORY";
		case VK_ERROR_OUT_OF_DEVICE_MEMORY:
			return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
		case VK_ERROR_INITIALIZATION_FAILED:
			return "VK_ERROR_INITIALIZATION_FAILED";
		case VK_ERROR_DEVICE_LOST:
			return "VK_ERROR_DEVICE_LOST";
		case VK_ERROR_LAYER_NOT_PRESENT:
			return "VK_ERROR_LAYER_NOT_PRESENT";
		case VK_ERROR_EXTENSION_NOT_PRESENT:
			return "VK_ERROR_EXTENSION_NOT_PRESENT";
		case VK_ERROR_FEATURE_NOT_PRESENT:
			return "VK_ERROR_FEATURE_NOT_PRESENT";
		case VK_ERROR_INCOMPATIBLE_DRIVER:
			return "VK_ERROR_INCOMPATIBLE_DRIVER";
		default:
			return "a Vulkan error";
	}
}

} // namespace roomprobe::vk
