// The Vulkan compute backend (gpu/compute_device.h) and its kernels, the GGX prefilter's gather
// (envmap/ggx_prefilter_gpu.h) and SH projection (envmap/sh_project_gpu.h), against their CPU
// twins, on gpu_test_device() (lavapipe in CI).

#include "engine/live_room.h"
#include "envmap/ggx_prefilter.h"
#include "envmap/ggx_prefilter_gpu.h"
#include "envmap/sh_project_gpu.h"
#include "gpu/compute_device.h"
#include "gpu_test_device.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <numbers>
#include <vector>

using namespace roomprobe;

namespace {

// A sky with a sharp bright light and a gradient: radiance 0.05 .. 20.
Cubemap test_sky(int p_size) {
	Cubemap map = make_cubemap(p_size);
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < p_size; y++) {
			for (int x = 0; x < p_size; x++) {
				const glm::dvec3 d = cubemap_direction(f, x, y, p_size);
				const float light = d.y > 0.9 && d.x > 0.1 ? 20.0f : 0.0f;
				map.faces[size_t(f)].at<cv::Vec3f>(y, x) = cv::Vec3f(float(0.5 + 0.45 * d.x) + light, float(0.3 + 0.25 * d.y), float(0.05 + 0.04 * (d.z + 1.0)));
			}
		}
	}
	return map;
}

} // namespace

TEST_CASE("GPU GGX: the chain on a Vulkan device equals the CPU's to the float rounding of each texel's taps") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	for (const int size : { 8, 32 }) {
		CAPTURE(size);
		const Cubemap sky = test_sky(size);
		const auto filter = std::make_shared<const GgxFilter>(size);
		const std::vector<Cubemap> cpu = filter->apply(sky);
		std::string error;
		const std::unique_ptr<GgxFilterGpu> gpu_filter = GgxFilterGpu::create(filter, device, &error);
		REQUIRE_MESSAGE(gpu_filter, error);
		for (int run = 0; run < 2; run++) { // the buffers are reused by the second map
			const std::vector<Cubemap> gpu = gpu_filter->apply(sky, &error);
			REQUIRE_MESSAGE(error.empty(), error);
			REQUIRE(gpu.size() == cpu.size());
			CHECK(gpu[0].faces[0].data == sky.faces[0].data); // level 0 shares the source's pixels
			// A texel is a convex sum (the weights sum to 1) of at most 4 taps a sample (bilinear, merged)
			// of values <= 20: each float addition rounds by at most 2^-24 of the running sum, so two
			// roundings of the same sums (the CPU may contract into FMAs, the GPU may not) differ by at
			// most 4 x samples x 2^-23 x 20.
			const double bound = 4.0 * double(filter->sample_count()) * std::ldexp(1.0, -23) * 20.0;
			double worst = 0.0;
			for (size_t level = 1; level < cpu.size(); level++) {
				REQUIRE(gpu[level].size == cpu[level].size);
				for (size_t f = 0; f < 6; f++) {
					worst = std::max(worst, cv::norm(gpu[level].faces[f], cpu[level].faces[f], cv::NORM_INF));
				}
			}
			MESSAGE("largest difference " << worst << " (bound " << bound << ")");
			CHECK(worst <= bound);
		}
	}
}

TEST_CASE("GPU GGX: the CPU backend asks for no device; a source of another size is refused with the reason") {
	std::string reason = "unchanged";
	CHECK(shared_compute_device(ComputeBackend::Cpu, &reason) == nullptr);
	CHECK(reason.empty());
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	std::string error;
	const std::unique_ptr<GgxFilterGpu> gpu_filter = GgxFilterGpu::create(std::make_shared<const GgxFilter>(8), device, &error);
	REQUIRE_MESSAGE(gpu_filter, error);
	CHECK(gpu_filter->apply(test_sky(16), &error).empty());
	CHECK(error.find("face size") != std::string::npos);
}

TEST_CASE("GPU GGX: an engine on the Vulkan backend makes the CPU engine's maps, and says which device it uses") {
	LiveRoomConfig config;
	config.has_rig = false;
	config.dense = false;
	config.has_room = true;
	config.floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 3.0 }, { 0.0, 3.0 } };
	config.floorplan.ceiling_height_m = 2.5;
	config.coarse.texel_size_m = 0.05;
	config.wait_for_ggx_filter = true;
	LiveRoom cpu_engine, gpu_engine;
	REQUIRE(cpu_engine.configure(config) == "");
	config.compute_backend = ComputeBackend::Vulkan;
	REQUIRE(gpu_engine.configure(config) == "");
	CHECK(cpu_engine.stats().compute == "CPU");
	CHECK(gpu_engine.stats().compute.rfind("Vulkan: ", 0) == 0);
	CHECK(gpu_engine.stats().compute_on_device);
	CHECK_FALSE(cpu_engine.stats().compute_on_device);
	const RoomMesh *mesh = cpu_engine.room_mesh();
	REQUIRE(mesh != nullptr);
	// A varied atlas: every texel its own colour.
	cv::Mat atlas(mesh->atlas_height, mesh->atlas_width, CV_32FC3);
	cv::randu(atlas, cv::Scalar::all(0.0), cv::Scalar::all(4.0));
	const glm::dvec3 at(2.0, 1.2, 1.5);
	std::shared_ptr<const ProbeMap> maps[2];
	LiveRoom *engines[2] = { &cpu_engine, &gpu_engine };
	for (int e = 0; e < 2; e++) {
		REQUIRE(engines[e]->set_atlas(atlas));
		const int probe = engines[e]->add_probe(at, 32);
		engines[e]->render_probes();
		maps[e] = engines[e]->probe_map(probe);
		REQUIRE(maps[e] != nullptr);
		REQUIRE(maps[e]->ggx_mips);
	}
	CHECK(gpu_engine.stats().stage_errors == 0);
	// Its SH came from the device too (the same rounding bound as the SH test, radiance <= 4 here).
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		CHECK(glm::length(maps[0]->sh[size_t(i)] - maps[1]->sh[size_t(i)]) <= 64.0 * std::ldexp(1.0, -24) * 4.0 * 0.7 * 4.0 * std::numbers::pi);
	}
	// The same atlas again: a new map whose faces are all the last one's (nothing filtered again,
	// converted or uploaded).
	REQUIRE(gpu_engine.set_atlas(atlas));
	gpu_engine.render_probes();
	const std::shared_ptr<const ProbeMap> again = gpu_engine.probe_map(maps[1]->probe);
	REQUIRE(again != nullptr);
	CHECK(again->version == maps[1]->version + 1);
	for (size_t f = 0; f < 6; f++) {
		CHECK(again->gpu_faces[f] == maps[1]->gpu_faces[f]);
	}
	REQUIRE(maps[0]->ggx_chain.size() == maps[1]->ggx_chain.size());
	// The same faces in (the coarse render runs on the CPU in both), so the chains differ only by
	// the float rounding of the taps' sums (the first test's bound, values <= 4 here).
	const double bound = 4.0 * double(shared_ggx_filter(32, true)->sample_count()) * std::ldexp(1.0, -23) * 4.0;
	for (size_t level = 0; level < maps[0]->ggx_chain.size(); level++) {
		for (size_t f = 0; f < 6; f++) {
			CHECK(cv::norm(maps[0]->ggx_chain[level].faces[f], maps[1]->ggx_chain[level].faces[f], cv::NORM_INF) <= bound);
		}
	}
}

TEST_CASE("GPU SH: the projection on a Vulkan device equals project_sh to the float rounding of a row's sums") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	for (const int size : { 16, 128 }) { // 128: box-filtered to 64 first, as project_sh does
		CAPTURE(size);
		const Cubemap sky = test_sky(size);
		const ShCoefficients cpu = project_sh(sky);
		std::string error;
		const std::unique_ptr<ShProjectorGpu> gpu = ShProjectorGpu::create(std::min(size, SH_PROJECTION_FACE_SIZE), device, &error);
		REQUIRE_MESSAGE(gpu, error);
		ShCoefficients sh;
		REQUIRE_MESSAGE(gpu->project(sky, &sh, &error), error);
		// A row's float sum of at most 64 products rounds by at most 64 x 2^-24 of the sum of their
		// magnitudes; over all rows that sum is at most max L x max |y| x 4 pi = 20 x 0.7 x 4 pi.
		double worst = 0.0;
		for (int i = 0; i < SH_COEFFICIENTS; i++) {
			for (int c = 0; c < 3; c++) {
				worst = std::max(worst, std::abs(sh[size_t(i)][c] - cpu[size_t(i)][c]));
			}
		}
		MESSAGE("largest SH difference " << worst);
		CHECK(worst <= 64.0 * std::ldexp(1.0, -24) * 20.0 * 0.7 * 4.0 * std::numbers::pi);
	}
	std::string error;
	const std::unique_ptr<ShProjectorGpu> wrong = ShProjectorGpu::create(32, device, &error);
	REQUIRE(wrong);
	ShCoefficients sh;
	CHECK_FALSE(wrong->project(test_sky(16), &sh, &error));
	CHECK(error.find("size") != std::string::npos);
}

TEST_CASE("GPU profile: each batch is counted by its kernels, and its device time lies within its wall time") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device(); // a device of its own: no other test's batches
	std::string error;
	const std::unique_ptr<ShProjectorGpu> gpu = ShProjectorGpu::create(16, device, &error);
	REQUIRE_MESSAGE(gpu, error);
	device->reset_batch_stats();
	ShCoefficients sh;
	for (int run = 0; run < 3; run++) {
		REQUIRE_MESSAGE(gpu->project(test_sky(16), &sh, &error), error);
	}
	const std::vector<GpuBatchStats> stats = device->batch_stats();
	REQUIRE(stats.size() == 1);
	CHECK(stats[0].kind == "sh_project");
	CHECK(stats[0].batches == 3);
	CHECK(stats[0].wall_ms > 0.0);
	MESSAGE("3 SH batches: wall " << stats[0].wall_ms << " ms, device " << (stats[0].timed ? std::to_string(stats[0].device_ms) + " ms" : "not timed"));
	if (stats[0].timed) { // the device's work lies between the recording and the fence's end: its clock may only round
		CHECK(stats[0].device_ms > 0.0);
		CHECK(stats[0].device_ms <= stats[0].wall_ms * 1.01 + 0.01);
	}
	device->reset_batch_stats();
	CHECK(device->batch_stats().empty());
}

TEST_CASE("GPU memory: buffers are placed by who reads them, counted while they live, and hold what the host wrote") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	const size_t device_before = device->device_memory_bytes(), host_before = device->host_memory_bytes();
	constexpr size_t BYTES = 1 << 20;
	std::string error;
	{
		const std::unique_ptr<GpuBuffer> input = device->make_buffer(BYTES, GpuAccess::DeviceReads, &error);
		const std::unique_ptr<GpuBuffer> output = device->make_buffer(BYTES, GpuAccess::HostReads, &error);
		REQUIRE_MESSAGE(input, error);
		REQUIRE_MESSAGE(output, error);
		MESSAGE("device-read buffer in device memory: " << input->in_device_memory() << ", host-read buffer: " << output->in_device_memory());
		const size_t in_device = (input->in_device_memory() ? BYTES : 0) + (output->in_device_memory() ? BYTES : 0);
		CHECK(device->device_memory_bytes() - device_before == in_device);
		CHECK(device->host_memory_bytes() - host_before == 2 * BYTES - in_device);
		// Both are mapped for the host: what it writes is there to read (the device's reads are the kernels' tests).
		std::vector<uint8_t> pattern(BYTES);
		for (size_t i = 0; i < BYTES; i++) {
			pattern[i] = uint8_t(i * 131 + 7);
		}
		std::memcpy(input->data(), pattern.data(), BYTES);
		std::memcpy(output->data(), pattern.data(), BYTES);
		CHECK(std::memcmp(input->data(), pattern.data(), BYTES) == 0);
		CHECK(std::memcmp(output->data(), pattern.data(), BYTES) == 0);
	}
	CHECK(device->device_memory_bytes() == device_before);
	CHECK(device->host_memory_bytes() == host_before);
}
