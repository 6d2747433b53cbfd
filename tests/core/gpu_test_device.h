#pragma once
// The Vulkan device of the GPU kernel tests (test_gpu_kernels.cpp, test_gpu_tracking.cpp): any
// device, Mesa's lavapipe (a CPU device) included, which is what CI has. Without one the test
// fails, naming why, rather than skip.

#include "gpu/compute_device.h"

#include <doctest/doctest.h>

#include <memory>
#include <string>

inline std::shared_ptr<roomprobe::ComputeDevice> gpu_test_device() {
	roomprobe::ComputeDeviceOptions options;
	options.allow_cpu_device = true; // lavapipe
	std::string error;
	std::shared_ptr<roomprobe::ComputeDevice> device = roomprobe::ComputeDevice::create(options, &error);
	REQUIRE_MESSAGE(device, "no Vulkan compute device: " << error);
	MESSAGE("Vulkan device: " << device->name() << std::string(device->is_cpu() ? " (a CPU device)" : ""));
	return device;
}
