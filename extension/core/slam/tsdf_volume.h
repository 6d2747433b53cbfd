#pragma once
// The dense colour model of the dense SLAM stage (paper §4.2, InfiniTAM's design): a truncated
// signed distance function with colour, stored sparsely in 8 x 8 x 8 voxel blocks that are found
// through a spatial hash and allocated only around observed surfaces. Depth frames are fused in
// with integrate(); raycast() gives the model seen from a pose (the reference for tracking).
// The per-voxel and per-pixel work is in tsdf_kernels.h.

#include <io/opencv.h>

#include "slam/slam_types.h"
#include "slam/tsdf_kernels.h"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace roomprobe {

class ComputeDevice;
class TsdfIntegratorGpu;
class TsdfRaycasterGpu;

struct TsdfOptions {
	float voxel_size_m = 0.01f; // edge of one voxel, metres
	float truncation_m = 0.04f; // half-width of the signed-distance band around surfaces, metres
	float color_band_m = 0.01f; // colour is averaged only into voxels this close to the surface, metres
	// Readings become point-to-plane distances: reading - z times the slope factor -n . x / z
	// of the surface's tangent plane there (n from the neighbouring readings), about the cosine of
	// the view angle. Readings whose factor is below this (0.3: surfaces tilted more than about
	// 72 deg from the ray), and those at depth edges, only carve free space; others are weighted
	// by the factor squared.
	float min_slope = 0.3f;
	// The tangent planes are taken on the depth smoothed over this radius (depth_pyramid.h
	// smooth_depth, pixels; 0: the raw depth), as ICP's normals are.
	int slope_smoothing_px = 1;
	int max_weight = 64; // cap on the running-average weight (head-on observations), 1..2047
	// Cap on the colour's running-average weight (frames): small, so that the colours follow a
	// change of the room's lighting within a few frames (§4.6) while the geometry keeps averaging
	// noise over many. 1..65535.
	int max_color_weight = 8;
	float min_depth_m = 0.3f; // depth readings (z, metres) outside [min, max] are ignored
	float max_depth_m = 4.0f;
	// Cap on allocated blocks (6 KiB each: 512 voxels of 12 bytes): 40000 blocks = 246 MB of
	// voxels plus a 2 MB hash table. See TsdfVolume for what happens at the cap.
	// Clamped to [1, 4194304]; a cap whose full model needs more than this machine's memory makes
	// the constructor throw std::runtime_error naming max_blocks (slam/tsdf_capacity.h).
	int max_blocks = 40000;
	// Integration skips the blocks and voxels that a frame cannot change (same result; false: every
	// voxel of every block in view is updated, the plain path the tests compare with).
	bool skip_unchanged = true;
	// Voxels updated eight at a time with AVX2 when the CPU has it, chosen at run time
	// (tsdf_integrate_simd.h); bit-identical to the scalar kernel (false: always scalar).
	bool simd = true;
};

// The last frames whose readings' bands crossed a block, newest first, and how many did in all.
struct TsdfSurfaceFrames {
	// Twice TsdfOptions::max_color_weight's default: at that cap the frames older than these hold
	// (8/9)^16, 15 % of a colour, and count as the oldest kept.
	static constexpr int KEPT = 16;
	uint32_t frames[KEPT] = {};
	uint32_t count = 0;
	int kept() const { return int(count < uint32_t(KEPT) ? count : uint32_t(KEPT)); }
	void add(uint32_t p_frame) {
		if (count > 0 && frames[0] == p_frame) {
			return; // the same frame again
		}
		for (int i = KEPT - 1; i > 0; i--) {
			frames[i] = frames[i - 1];
		}
		frames[0] = p_frame;
		count++;
	}
};

// What one integrate() did.
struct IntegrationStats {
	int valid_pixels = 0; // depth readings used
	int visible_blocks = 0; // blocks in view: along the readings' bands, plus allocated ones in view
	// Those of them whose voxels were updated: the others could not change (wholly behind the
	// readings under them, over no reading, or free space already at +1 with the full weight).
	int updated_blocks = 0;
	int allocated_blocks = 0; // blocks newly allocated by this frame
	int evicted_blocks = 0; // blocks evicted by this frame to stay under max_blocks
	int dropped_blocks = 0; // blocks this frame wanted but could not have (its own view exceeded the cap)
};

// The state of the whole volume.
struct TsdfStats {
	int allocated_blocks = 0;
	int capacity_blocks = 0; // max_blocks
	size_t bytes_used = 0; // voxel pool in use (allocated blocks) plus the hash table, bytes
	size_t bytes_reserved = 0; // voxel pool held (it does not shrink on eviction) plus the hash table, bytes
	long long evicted_blocks_total = 0;
	long long dropped_blocks_total = 0;
	// World-space box of the allocated blocks, metres (both 0 when none is allocated).
	glm::vec3 bounds_min = glm::vec3(0.0f), bounds_max = glm::vec3(0.0f);
};

// What one raycast() did.
struct RaycastStats {
	int hit_pixels = 0;
	long long steps = 0; // samples along all rays (a measure of the empty-space skipping)
};

// The voxel-hashed colour TSDF.
//
// Memory policy: at most max_blocks blocks are allocated. When a frame needs new blocks beyond
// the cap, blocks outside the frame's view (neither along its readings nor projecting into it in
// front of the reading there: hidden blocks count as out of view) are evicted, farthest first from the nearest keep-point (set_keep_points, e.g. the light
// probes; the camera position when none is set), and their voxels are lost. Blocks in view are
// never evicted; when the view alone needs more than the cap, the new blocks farthest from the
// keep-points are not allocated (dropped_blocks) and those readings go unfused.
class TsdfVolume {
public:
	explicit TsdfVolume(const TsdfOptions &p_options = TsdfOptions());
	~TsdfVolume();
	TsdfVolume(TsdfVolume &&) noexcept;
	TsdfVolume &operator=(TsdfVolume &&) noexcept;

	// Where integrate() updates voxels and raycast() marches (issue #40): on p_device, with the
	// voxel pool moved into memory the device shares with the host (tsdf_integrate_gpu.h: the
	// whole max_blocks pool is held from now on; tsdf_raycast_gpu.h), or on the CPU when it is
	// null (the pool moves back). The model is kept either way. "" or compute_problem()'s words
	// for what the device cannot do (that then stays on the CPU).
	// p_window_blocks: TsdfIntegratorGpu::create's (0: the device's reach; tests ask for fewer).
	std::string set_compute(std::shared_ptr<ComputeDevice> p_device, size_t p_window_blocks = 0);
	// Whether integration and raycasts run on a device now, and, when set_compute's device refused
	// or a dispatch failed and put either back on the CPU, which and why: "integration on the CPU
	// (why)", "raycasts on the CPU (why)", joined by "; " ("" otherwise).
	// Safe from any thread (the engine's stats read them while the SLAM worker fuses).
	bool integrates_on_gpu() const;
	bool raycasts_on_gpu() const;
	std::string compute_problem() const;

	// Fuses one frame. p_depth_m: CV_32FC1, z in metres, NaN or 0 = no reading; p_rgb: CV_8UC3,
	// R, G, B, same size; p_camera: the (undistorted) camera of both; p_world_from_camera: its pose.
	// Blocks along each reading's ray within [d - truncation, d + truncation] are allocated; then
	// every voxel of the blocks in view is updated (parallel over blocks; blocks and voxels it
	// cannot change are skipped). Blocks whose voxels changed are marked dirty (take_dirty_blocks).
	IntegrationStats integrate(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera);

	// The model seen from a pose: per pixel the first + to - zero crossing of the tsdf along the
	// ray within [min_depth, max_depth] (and within the depth range of the allocated blocks that
	// project near the pixel), with every field of r_maps filled (points and normals in
	// world frame, depth = camera z; NaN and colour 0 where no surface was met). Parallel over rows.
	void raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, ModelMaps *r_maps, RaycastStats *r_stats = nullptr) const;
	// The same within [p_min_depth_m, p_max_depth_m] of camera z instead of the options' depth
	// range (a probe's cubemap faces: surfaces a few centimetres away count). Without
	// p_normals, normals stay NaN and a hit costs six trilinear reads less (a dense pass).
	void raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_min_depth_m, float p_max_depth_m, ModelMaps *r_maps,
			RaycastStats *r_stats = nullptr, bool p_normals = true) const;
	// The same with a search interval per pixel: p_search_m (CV_32FC2, the camera's size) holds
	// [near, far] camera z; pixels with a finite interval march only there (the tracking
	// reference, searched around the frame just fused: a surface of the model outside it is not
	// found), the others as above.
	void raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, const cv::Mat &p_search_m, ModelMaps *r_maps,
			RaycastStats *r_stats = nullptr, bool p_normals = true) const;

	// Trilinear tsdf (normalised, [-1, 1]) and colour (0..255, zero when no voxel around has one)
	// at a world point (metres); false where a voxel around it is unallocated or unobserved.
	bool sample_tsdf(const glm::vec3 &p_world, float *r_tsdf, glm::vec3 *r_rgb) const;

	// Points (world metres) whose neighbourhood eviction spares longest.
	void set_keep_points(const std::vector<glm::dvec3> &p_points);

	// Blocks changed (updated or evicted) since the last call, sorted, each once.
	std::vector<glm::ivec3> take_dirty_blocks();

	// Frees every block; options and keep-points stay.
	void reset();

	TsdfStats stats() const;
	const TsdfOptions &options() const { return m_options; }

	// The 512 voxels of a block (index tsdf_local_index), or nullptr when it is not allocated.
	const TsdfVoxel *find_block(const glm::ivec3 &p_block) const;
	// Frames fused so far (integrate() calls over the volume's life; reset() keeps counting).
	uint32_t frame_count() const { return m_frame; }
	// The frames (frame_count() then) whose readings' truncation bands crossed the block at world
	// point p_world, metres: when its surface colours were fused, the last few of them (empty
	// when not allocated). The dense colours' lighting is per block by them (envmap/
	// dense_render.h, issue #42).
	TsdfSurfaceFrames surface_frames(const glm::vec3 &p_world) const { return surface_frames(block_at(p_world)); }
	TsdfSurfaceFrames surface_frames(const glm::ivec3 &p_block) const;
	// The block holding the voxel nearest world point p_world, metres.
	glm::ivec3 block_at(const glm::vec3 &p_world) const;
	// Integer coordinates of every allocated block, sorted.
	std::vector<glm::ivec3> allocated_blocks() const;
	// Read-only access for kernels; valid until the next integrate() or reset().
	TsdfView view() const;
	// Per cell of DEPTH_RANGE_CELL_PX^2 pixels (CV_32FC2), the [min, max] camera depth of the
	// allocated blocks that project onto it, within [p_near_m, p_far_m] (+inf, -inf: none):
	// where a raycast marches each pixel (InfiniTAM's expected depths).
	static constexpr int DEPTH_RANGE_CELL_PX = 8;
	cv::Mat depth_ranges(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_near_m, float p_far_m) const;

private:
	void collect_band_blocks(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, std::vector<glm::ivec3> *r_blocks, int *r_valid_pixels) const;
	void mark_blocks_in_view(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera);
	float keep_distance2(const glm::ivec3 &p_block, const Pose &p_world_from_camera) const;
	int evict_for(int p_needed, const Pose &p_world_from_camera);
	int32_t allocate_slot(const glm::ivec3 &p_block);
	void free_slot(int32_t p_slot);
	void update_bounds();
	TsdfVoxel *pool();
	const TsdfVoxel *pool() const;
	void leave_device(); // the pool back in host memory
	// Step 4 of integrate(): every voxel of the blocks in view (p_depth: clean), on the device
	// when there is one, else on the CPU.
	void update_in_view(const cv::Mat &p_depth, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, IntegrationStats *r_stats);
	// Its update on the device: false (after leave_device, with the reason kept) when it failed.
	bool update_on_device(const TsdfFrameView &p_frame, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y, const glm::vec3 &p_step_z,
			const std::vector<int32_t> &p_visible, const std::vector<glm::vec3> &p_origins, std::vector<uint8_t> *r_updated, std::vector<uint8_t> *r_changed);
	void raycast_ranged(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_min_depth_m, float p_max_depth_m, const cv::Mat *p_search_m,
			bool p_normals, ModelMaps *r_maps, RaycastStats *r_stats) const;

	// Hash table (open addressing, linear probing, backward-shift deletion).
	int32_t *hash_lookup(const glm::ivec3 &p_block);
	bool hash_insert(const glm::ivec3 &p_block, int32_t p_slot);
	void hash_erase(const glm::ivec3 &p_block);

	TsdfOptions m_options;
	std::vector<TsdfHashEntry> m_hash;
	uint32_t m_hash_mask = 0;
	int m_hash_used = 0;

	std::vector<TsdfVoxel> m_voxels; // pool: slot s at [s * 512, s * 512 + 512); empty while m_gpu holds it
	std::unique_ptr<TsdfIntegratorGpu> m_gpu; // set_compute's device, with the pool
	std::unique_ptr<TsdfRaycasterGpu> m_gpu_raycaster; // on m_gpu's pool (reset before it)
	// Where the kernels run and why not, for readers on other threads; written by set_compute and
	// by a failed dispatch (integrate() on the fusing thread, a raycast on any reader's).
	struct ComputeStatus {
		mutable std::mutex mutex;
		bool integrating = false, raycasting = false;
		std::string integration_problem, raycast_problem;
	};
	std::unique_ptr<ComputeStatus> m_status = std::make_unique<ComputeStatus>(); // a pointer: the volume stays movable
	void set_status(bool p_integrating, bool p_raycasting, const std::string &p_integration_problem, const std::string &p_raycast_problem) const;
	uint64_t m_hash_version = 0; // changes with the hash table (the device's copy follows it)
	std::vector<glm::ivec3> m_slot_block; // the block held by each slot
	std::vector<uint8_t> m_slot_used;
	std::vector<uint32_t> m_slot_frame; // the frame that last saw each slot (in view)
	std::vector<TsdfSurfaceFrames> m_slot_surface; // the frames whose readings' bands crossed each slot
	std::vector<uint8_t> m_slot_saturated; // every voxel at tsdf +1 with max_weight (free space seen long enough)
	std::vector<int32_t> m_free_slots;
	int m_allocated = 0;
	uint32_t m_frame = 0;

	std::vector<glm::dvec3> m_keep_points;
	std::vector<glm::ivec3> m_dirty;
	long long m_evicted_total = 0;
	long long m_dropped_total = 0;
	glm::vec3 m_bounds_min = glm::vec3(0.0f), m_bounds_max = glm::vec3(0.0f);
};

} // namespace roomprobe
