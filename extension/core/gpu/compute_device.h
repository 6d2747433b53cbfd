#pragma once
// ComputeDevice: the Vulkan compute backend's device (issue #40): one queue that runs compute
// kernels (GLSL compiled to SPIR-V by glslc at build time, embedded in the library) over storage
// buffers. Kernels stay device-agnostic in what they compute: each has a CPU twin that the tests
// hold it to. A stage asks for the device through the engine's configuration and falls back to
// its CPU code, with the reason, when there is none.
//
// Buffers are host-visible and coherent (mapped once), placed by who reads them (GpuAccess): what
// the host writes and the device reads lives in device memory the host can map where the device
// has it (a discrete GPU's BAR; the H200's profile showed its kernels crawling over host memory),
// and what the host reads lives in host-cached memory. On integrated GPUs and lavapipe both are
// the one memory. One lock serialises the queue: a batch of dispatches is recorded, submitted and
// waited for under it.

#include "vulkan_api.h"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

namespace roomprobe {

enum class ComputeBackend {
	Cpu, // the CPU kernels only
	Vulkan, // Vulkan compute; any device, Mesa's lavapipe (a CPU device) included
	Auto, // Vulkan where a device that is not a CPU exists, else the CPU kernels
};

const char *compute_backend_name(ComputeBackend p_backend); // "cpu", "vulkan", "auto"
// The backend a command line or file names (compute_backend_name's words); false for any other.
bool compute_backend_from_name(const std::string &p_name, ComputeBackend *r_backend);

class ComputeDevice;

// Where the kernels run, as the engine's stats().compute and the benchmark say it: "Vulkan:
// <device>" on p_device, else "CPU" when p_asked is the CPU, else "CPU (<backend>: <p_why_not>)".
std::string compute_backend_note(ComputeBackend p_asked, const ComputeDevice *p_device, const std::string &p_why_not);

struct ComputeDeviceOptions {
	bool allow_cpu_device = true; // false: refuse a CPU device (lavapipe), as Auto does
};

// Who reads a buffer, which decides its memory.
enum class GpuAccess {
	// The host only writes it (in order, never reading it back), the device reads it: device memory
	// the host can map where there is such memory (write-combined: host reads of it crawl), else
	// host memory.
	DeviceReads,
	// The host reads it (the device's results, or a model both work on): host-cached memory where
	// the device has it, since the host reads write-combined memory a bus transaction at a time.
	HostReads,
};

// A storage buffer, mapped for the host.
class GpuBuffer {
public:
	~GpuBuffer();
	GpuBuffer(const GpuBuffer &) = delete;
	GpuBuffer &operator=(const GpuBuffer &) = delete;
	size_t size_bytes() const { return bytes; }
	void *data() const { return mapped; }
	bool in_device_memory() const { return device_local; } // device-local memory (a discrete GPU's own)

private:
	friend class ComputeDevice;
	GpuBuffer() = default;
	const ComputeDevice *device = nullptr;
	VkBuffer buffer = VK_NULL_HANDLE;
	VkDeviceMemory memory = VK_NULL_HANDLE;
	void *mapped = nullptr;
	size_t bytes = 0;
	bool device_local = false;
};

// A compute pipeline: SPIR-V with p_buffers storage buffers at bindings 0 .. p_buffers - 1 of set
// 0, and p_push_bytes of push constants.
class GpuKernel {
public:
	~GpuKernel();
	GpuKernel(const GpuKernel &) = delete;
	GpuKernel &operator=(const GpuKernel &) = delete;
	int buffer_count() const { return buffers; }
	const std::string &label() const { return name; }

private:
	friend class ComputeDevice;
	GpuKernel() = default;
	std::string name; // the kernel's file name, for the batches' figures
	const ComputeDevice *device = nullptr;
	VkShaderModule module = VK_NULL_HANDLE;
	VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
	VkPipelineLayout layout = VK_NULL_HANDLE;
	VkPipeline pipeline = VK_NULL_HANDLE;
	int buffers = 0;
	uint32_t push_bytes = 0;
};

// The part of a buffer a dispatch binds: a buffer may be larger than one binding may reach
// (maxStorageBufferRange; lavapipe's is 128 MiB). offset: a multiple of the device's
// minStorageBufferOffsetAlignment; bytes 0: to the end.
struct GpuWindow {
	size_t offset = 0, bytes = 0;
};

// One dispatch of a batch: the kernel, its buffers in binding order, its push constants and the
// workgroup counts.
struct GpuDispatch {
	const GpuKernel *kernel = nullptr;
	std::vector<const GpuBuffer *> buffers;
	std::vector<GpuWindow> windows; // per buffer, or empty: every buffer whole
	std::vector<uint8_t> push;
	uint32_t groups_x = 1, groups_y = 1, groups_z = 1;

	// The push constants: p_values byte for byte (a value or a struct laid out as the kernel's).
	template <typename T>
	void set_push(const T &p_values) {
		static_assert(std::is_trivially_copyable_v<T>);
		push.resize(sizeof(T));
		std::memcpy(push.data(), &p_values, sizeof(T));
	}
};

// What the device's batches of one kind cost (ComputeDevice::batch_stats): the kind is the batch's
// kernels' labels joined by '+'. wall: from the recording of the commands to the end of the fence's
// wait, on the calling thread; device: the device's own timestamps at the batch's start and end
// (where the queue has them). wall - device is the host's share: recording, submission, wake-up.
struct GpuBatchStats {
	std::string kind;
	size_t batches = 0;
	double wall_ms = 0.0, device_ms = 0.0; // sums over the batches
	bool timed = false; // device_ms is measured
};

class ComputeDevice {
public:
	// A device with a compute queue, GPUs before CPU devices, the next tried where one's driver
	// refuses. Null, with r_error naming what is missing (no loader, no device, each device's
	// failed call), where there is none.
	static std::shared_ptr<ComputeDevice> create(const ComputeDeviceOptions &p_options, std::string *r_error);
	~ComputeDevice();
	ComputeDevice(const ComputeDevice &) = delete;
	ComputeDevice &operator=(const ComputeDevice &) = delete;

	const std::string &name() const { return device_name; } // "llvmpipe (LLVM 19.1.7, 256 bits)", ...
	bool is_cpu() const { return cpu; }

	// A buffer in the memory p_access asks for (GpuAccess), null with r_error where none can be had.
	std::unique_ptr<GpuBuffer> make_buffer(size_t p_bytes, GpuAccess p_access, std::string *r_error) const;
	// *r_buffer made anew, p_bytes + p_slack_bytes large, unless it already holds p_bytes (a
	// stage's buffers grow with its inputs and are kept between calls). False with r_error.
	bool ensure_buffer(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error, size_t p_slack_bytes = 0) const;
	// The buffers' bytes now in device-local memory and in host memory (the figures say where the
	// data lives).
	size_t device_memory_bytes() const { return device_bytes.load(); }
	size_t host_memory_bytes() const { return host_bytes.load(); }
	// p_label: the kernel's name in the batches' figures (its file's, "icp_reduce").
	std::unique_ptr<GpuKernel> make_kernel(const uint32_t *p_spirv, size_t p_words, int p_buffers, uint32_t p_push_bytes, std::string *r_error,
			const char *p_label = "kernel") const;
	// Runs the dispatches in order (each sees the writes of those before it) and waits for them.
	// "" or what failed.
	std::string run(const std::vector<GpuDispatch> &p_dispatches) const;
	// The batches run so far, by kind (a profile of the device path: where its time goes), and a
	// fresh start of it.
	std::vector<GpuBatchStats> batch_stats() const;
	void reset_batch_stats() const;

	const vk::Api &api() const { return vk_api; }
	const VkPhysicalDeviceLimits &limits() const { return device_limits; }
	// A batch whose wait failed (timeout, device lost) may still be running: the device refuses
	// every later batch, and the stages stay on the CPU.
	bool is_lost() const { return lost.load(); }
	// Fault injection (the tests' lost GPU): every later batch is refused as after a real loss.
	void simulate_loss() const { lost = true; }
	VkDevice handle() const { return device; }

private:
	friend class GpuBuffer; // its memory's bytes, counted here
	ComputeDevice() = default;
	// A physical device that can run compute, and its rank (GPUs first).
	struct Candidate {
		VkPhysicalDevice physical = VK_NULL_HANDLE;
		uint32_t family = 0; // a queue family with compute
		int rank = 0;
		VkPhysicalDeviceProperties properties{};
		std::string name;
		uint32_t timestamp_bits = 0; // the queue family's timestampValidBits (0: none)
	};
	std::string open(const ComputeDeviceOptions &p_options);
	std::vector<Candidate> rank_devices(const std::vector<VkPhysicalDevice> &p_devices, const ComputeDeviceOptions &p_options) const;
	std::string open_device(const Candidate &p_candidate); // "" or why it cannot be used
	void close_device(); // what open_device made, so that the next candidate can be tried
	// Adds a finished batch to batch_stats(), with its device time where the queue has timestamps.
	void record_batch(const std::vector<GpuDispatch> &p_dispatches, double p_wall_ms) const;
	// A host-visible, coherent memory type among p_bits: with p_also's flags and none of p_avoid's
	// where one has them, else the nearest to that; -1: none.
	int memory_type(uint32_t p_bits, VkMemoryPropertyFlags p_also = 0, VkMemoryPropertyFlags p_avoid = 0) const;
	// Memory of type p_type for r_buffer's buffer, bound and mapped; "" or what failed.
	std::string bind_memory(GpuBuffer *r_buffer, VkMemoryRequirements p_needs, int p_type) const;

	vk::Api vk_api;
	VkInstance instance = VK_NULL_HANDLE;
	VkPhysicalDevice physical = VK_NULL_HANDLE;
	VkDevice device = VK_NULL_HANDLE;
	VkQueue queue = VK_NULL_HANDLE;
	VkCommandPool pool = VK_NULL_HANDLE;
	VkCommandBuffer commands = VK_NULL_HANDLE;
	VkFence fence = VK_NULL_HANDLE;
	VkDescriptorPool descriptors = VK_NULL_HANDLE;
	VkQueryPool timestamps = VK_NULL_HANDLE; // two a batch, where the queue has them
	uint64_t timestamp_mask = 0;
	mutable std::map<std::string, GpuBatchStats> batches; // by kind, under queue_mutex
	VkPhysicalDeviceMemoryProperties memory{};
	VkPhysicalDeviceLimits device_limits{};
	mutable std::atomic<bool> lost{ false };
	mutable std::atomic<size_t> device_bytes{ 0 }, host_bytes{ 0 };
	std::string device_name;
	bool cpu = false;
	mutable std::mutex queue_mutex;
};

// The process's device for p_backend (created once, shared): null for Cpu, and null with
// r_reason saying why when Vulkan or Auto find none (Auto also when the only device is a CPU one).
std::shared_ptr<ComputeDevice> shared_compute_device(ComputeBackend p_backend, std::string *r_reason);

} // namespace roomprobe
