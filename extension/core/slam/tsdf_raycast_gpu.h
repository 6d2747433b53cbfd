#pragma once
// TSDF raycasts on a Vulkan compute device (issue #40): tsdf_raycast.comp runs every pixel's
// march of TsdfVolume::raycast on the voxel pool that TsdfIntegratorGpu shares with the CPU, for
// the tracking reference and a probe's dense faces alike. The host computes each 8x8 cell's depth
// range (TsdfVolume::depth_ranges, a pass over the allocated blocks), uploads the hash table when
// it changed, and turns the hits into ModelMaps.
//
// Tolerance against the CPU: the same operations in the same order, multiply-adds kept apart; a
// device whose division and square root are correctly rounded (lavapipe's are) gives the CPU's
// maps bit for bit. Elsewhere a ray's samples move by float rounding, which moves a hit by far
// less than a voxel, except where a sample sits on a voxel boundary or a sign change
// (tests/core/test_gpu_raycast.cpp).

#include "slam_types.h"
#include "tsdf_kernels.h"

#include <gpu/compute_device.h>
#include <io/opencv.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace roomprobe {

class TsdfIntegratorGpu;
struct RaycastStats;

// What one raycast needs besides the pool: TsdfVolume's state and the ray limits.
struct TsdfRaycastInput {
	PinholeIntrinsics camera;
	Pose world_from_camera;
	float min_depth_m = 0.3f, max_depth_m = 4.0f;
	glm::vec3 bounds_min = glm::vec3(0.0f), bounds_max = glm::vec3(0.0f); // allocated blocks, world metres
	bool normals = true;
	const cv::Mat *ranges = nullptr; // CV_32FC2 per 8x8 cell (depth_ranges)
	const cv::Mat *search_m = nullptr; // CV_32FC2 per pixel, or null
	const TsdfHashEntry *hash = nullptr;
	uint32_t hash_mask = 0;
	uint64_t hash_version = 0; // changes whenever the table does: uploaded only then
	float voxel_size_m = 0.01f, truncation_m = 0.04f;
};

class TsdfRaycasterGpu {
public:
	static constexpr int MAX_WINDOWS = 4; // the pool's windows the kernel binds

	// Null, with r_error, when the kernel cannot be made or p_pool spans more than MAX_WINDOWS windows.
	static std::unique_ptr<TsdfRaycasterGpu> create(const TsdfIntegratorGpu &p_pool, std::string *r_error);

	// The model seen as p_input says into r_maps (as TsdfVolume::raycast fills them); false when a
	// buffer or the dispatch failed, after which failure() says why and the raycaster is not used
	// again (its device may be lost). Thread-safe: raycasts take turns.
	bool raycast(const TsdfRaycastInput &p_input, ModelMaps *r_maps, RaycastStats *r_stats) const;
	bool has_failed() const;
	std::string failure() const;

private:
	TsdfRaycasterGpu(const TsdfIntegratorGpu &p_pool) :
			pool(p_pool) {}

	const TsdfIntegratorGpu &pool; // outlives this (TsdfVolume owns both)
	std::unique_ptr<GpuKernel> kernel;
	mutable std::mutex busy; // the buffers below, one raycast at a time
	mutable std::unique_ptr<GpuBuffer> hash, ranges, hits, params;
	mutable uint64_t uploaded_version = ~uint64_t(0);
	mutable std::string failed_because; // under busy
	bool run(const TsdfRaycastInput &p_input, ModelMaps *r_maps, RaycastStats *r_stats, std::string *r_error) const;
};

} // namespace roomprobe
