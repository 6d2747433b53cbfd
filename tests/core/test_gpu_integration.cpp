// TSDF integration on a Vulkan device (slam/tsdf_integrate_gpu.h) against the CPU's, voxel by
// voxel, on the synthetic living room at 320x240, on gpu_test_device() (lavapipe in CI).
//
// The tolerance: the device runs tsdf_update_voxel_at's operations in the same order with no
// fused multiply-adds, so where its division is correctly rounded (lavapipe's is) the voxels are
// the CPU's bit for bit, and the test holds lavapipe to that. Vulkan allows a GPU's division
// 2.5 ulp of error: a voxel's tsdf then moves by a few ulp per frame (5e-7 relative; under 1e-5
// after the capped running average), and a voxel whose projection lands within that of a pixel
// boundary reads the neighbouring pixel. On other devices the test allows those: tsdf within
// 1e-5, and at most 1 voxel in 1000 with another weight, colour or a larger tsdf difference.

#include "gpu_test_device.h"
#include "gpu_test_fusion.h"
#include "slam/tsdf_volume.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>

using namespace roomprobe;
using namespace synth_frames;
using gpu_test_fusion::fuse;

namespace {

struct VoxelDifference {
	size_t observed = 0; // voxels with a weight in either volume
	size_t other = 0; // another weight, colour weight or colour, or a tsdf more than 1e-5 apart
	size_t bits_differ = 0; // any byte differs
	float tsdf = 0.0f; // the largest tsdf difference among the others
};

VoxelDifference compare_volumes(const TsdfVolume &p_cpu, const TsdfVolume &p_gpu) {
	VoxelDifference out;
	const std::vector<glm::ivec3> blocks = p_cpu.allocated_blocks();
	REQUIRE(blocks == p_gpu.allocated_blocks());
	for (const glm::ivec3 &block : blocks) {
		const TsdfVoxel *a = p_cpu.find_block(block), *b = p_gpu.find_block(block);
		for (int i = 0; i < TSDF_BLOCK_VOXELS; i++) {
			if (a[i].weight == 0 && b[i].weight == 0) {
				continue;
			}
			out.observed++;
			if (std::memcmp(&a[i], &b[i], sizeof(TsdfVoxel)) != 0) {
				out.bits_differ++;
			}
			const float d = std::abs(a[i].tsdf - b[i].tsdf);
			if (a[i].weight != b[i].weight || a[i].color_weight != b[i].color_weight || a[i].r != b[i].r || a[i].g != b[i].g || a[i].b != b[i].b ||
					d > 1e-5f) {
				out.other++;
			} else {
				out.tsdf = std::max(out.tsdf, d);
			}
		}
	}
	return out;
}

void check_close(const VoxelDifference &p_difference, bool p_cpu_device) {
	MESSAGE(p_difference.observed, " observed voxels; ", p_difference.bits_differ, " differ in any bit, ", p_difference.other,
			" beyond float rounding; largest tsdf difference among the rest ", p_difference.tsdf);
	CHECK(p_difference.observed > 100000);
	if (p_cpu_device) {
		CHECK(p_difference.bits_differ == 0); // lavapipe: correctly rounded division, no fusing
	}
	CHECK(p_difference.other <= p_difference.observed / 1000);
	CHECK(p_difference.tsdf <= 1e-5f);
}

} // namespace

TEST_CASE("GPU TSDF: integration on a Vulkan device gives the CPU's voxels, block lists and changed blocks") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	TsdfVolume cpu, gpu;
	REQUIRE(gpu.set_compute(device) == "");
	REQUIRE(gpu.integrates_on_gpu());
	for (int i = 0; i < 12; i++) {
		CAPTURE(i);
		const IntegrationStats a = fuse(&cpu, i), b = fuse(&gpu, i);
		CHECK(b.valid_pixels == a.valid_pixels);
		CHECK(b.visible_blocks == a.visible_blocks);
		CHECK(b.updated_blocks == a.updated_blocks);
		CHECK(b.allocated_blocks == a.allocated_blocks);
		if (device->is_cpu()) {
			CHECK(gpu.take_dirty_blocks() == cpu.take_dirty_blocks());
		}
	}
	CHECK(gpu.compute_problem() == "");
	CHECK(gpu.integrates_on_gpu());
	check_close(compare_volumes(cpu, gpu), device->is_cpu());
	// The whole pool is held on the device (stats say so).
	CHECK(gpu.stats().bytes_reserved >= size_t(gpu.options().max_blocks) * TSDF_BLOCK_VOXELS * sizeof(TsdfVoxel));
}

TEST_CASE("GPU TSDF: the slope factors made on the device follow slope_smoothing_px, none included") {
	// The device smooths the depth (depth_smooth.comp) and takes the tangent planes on it
	// (tsdf_slope.comp); radius 0 takes them on the clean depth itself.
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	for (const int radius : { 0, 2 }) {
		CAPTURE(radius);
		TsdfOptions options;
		options.slope_smoothing_px = radius;
		TsdfVolume cpu(options), gpu(options);
		REQUIRE(gpu.set_compute(device) == "");
		for (int i = 0; i < 4; i++) {
			fuse(&cpu, i);
			fuse(&gpu, i);
		}
		CHECK(gpu.integrates_on_gpu());
		check_close(compare_volumes(cpu, gpu), device->is_cpu());
	}
}

TEST_CASE("GPU TSDF: the model moves to the device and back with set_compute, and fusing goes on where it left off") {
	// A volume fused on the CPU, then on the device, then on the CPU again, against one fused on the
	// CPU throughout: the same voxels (to the device's rounding), so nothing is lost or doubled in
	// either move.
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	TsdfVolume cpu, moved;
	for (int i = 0; i < 9; i++) {
		if (i == 3) {
			REQUIRE(moved.set_compute(device) == "");
		}
		if (i == 6) {
			REQUIRE(moved.set_compute(nullptr) == "");
			CHECK(!moved.integrates_on_gpu());
		}
		fuse(&cpu, i);
		fuse(&moved, i);
	}
	check_close(compare_volumes(cpu, moved), device->is_cpu());
}

TEST_CASE("GPU TSDF: a device lost while fusing puts fusion and raycasts back on the CPU, with the reason, and loses no frame") {
	// A lost device refuses every later batch before it starts (ComputeDevice::run), as after a
	// wait that failed: the frame whose batch was refused is fused on the CPU, whole.
	const std::shared_ptr<ComputeDevice> device = gpu_test_device(); // its own: the loss stays in this test
	TsdfVolume cpu, gpu;
	REQUIRE(gpu.set_compute(device) == "");
	for (int i = 0; i < 6; i++) {
		if (i == 3) {
			device->simulate_loss();
		}
		fuse(&cpu, i);
		fuse(&gpu, i);
	}
	const std::string problem = gpu.compute_problem();
	CAPTURE(problem);
	CHECK(!gpu.integrates_on_gpu());
	CHECK(!gpu.raycasts_on_gpu());
	CHECK(problem.rfind("integration on the CPU (integration on the GPU failed: the Vulkan device was lost", 0) == 0);
	CHECK(problem.find("; raycasts on the CPU (") != std::string::npos);
	check_close(compare_volumes(cpu, gpu), device->is_cpu());
	ModelMaps maps;
	RaycastStats stats;
	gpu.raycast(pinhole_intrinsics(half_camera()), living_room().trajectory.world_from_rgb(0.6), &maps, &stats);
	CHECK(stats.hit_pixels > 1000); // on the CPU now
}

TEST_CASE("GPU TSDF: a pool larger than one binding reaches is fused a window at a time, with the same voxels") {
	// lavapipe binds at most 128 MiB (maxStorageBufferRange), a third of a pool of 60000 blocks:
	// the pool is one buffer, bound in windows, one dispatch each. Here windows of 300 blocks,
	// so that this room's few thousand blocks span many.
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	TsdfVolume cpu, windowed;
	// The raycast binds at most four windows: it stays on the CPU and says so, naming what to lower.
	const std::string problem = windowed.set_compute(device, 300);
	CAPTURE(problem);
	REQUIRE(windowed.integrates_on_gpu());
	CHECK(!windowed.raycasts_on_gpu());
	CHECK(problem.rfind("raycasts on the CPU (the raycast on the GPU: the voxel pool spans ", 0) == 0);
	CHECK(problem.find("lower max_blocks") != std::string::npos);
	for (int i = 0; i < 6; i++) {
		fuse(&cpu, i);
		fuse(&windowed, i);
	}
	REQUIRE(cpu.stats().allocated_blocks > 3 * 300);
	CHECK(windowed.compute_problem() == problem);
	check_close(compare_volumes(cpu, windowed), device->is_cpu());
}
