// TsdfVolume (tsdf_volume.h): its construction, the block hash table, the voxel pool and its
// eviction under the memory cap, and the queries. Integration is in tsdf_volume_integrate.cpp,
// the raycasts in tsdf_volume_raycast.cpp (split by concern to keep each file short).
#include "tsdf_volume.h"

#include "tsdf_capacity.h"
#include "tsdf_integrate_gpu.h"
#include "tsdf_raycast_gpu.h"
#include "tsdf_volume_internal.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <new>
#include <stdexcept>

namespace roomprobe {

using tsdf_volume_internal::block_centre;

namespace {

// The hash table is kept at most this full (linear probing degrades beyond).
constexpr double MAX_HASH_LOAD = 0.75;

constexpr int TSDF_MAX_BLOCKS = 1 << 22;

uint32_t hash_size_for(int p_max_blocks) {
	uint32_t size = 1024;
	while (double(size) * MAX_HASH_LOAD < 1.5 * double(p_max_blocks)) {
		size *= 2;
	}
	return size;
}

} // namespace

TsdfVolume::TsdfVolume(const TsdfOptions &p_options) :
		m_options(p_options) {
	// 1 << 22 blocks is 24 GiB of voxels: beyond any machine this runs on, and the hash table's
	// size (a power of two of 32 bits) would overflow past it.
	m_options.max_blocks = std::clamp(m_options.max_blocks, 1, TSDF_MAX_BLOCKS);
	m_options.max_weight = std::clamp(m_options.max_weight, 1, 65535 / TSDF_WEIGHT_UNIT);
	// A cap this machine cannot hold is refused, naming it and the memory it needs (issue #38: the
	// top of the range ended in a bare std::bad_alloc from the reservation below).
	const std::string too_big = tsdf_capacity_problem("max_blocks", m_options.max_blocks, physical_memory_bytes());
	if (!too_big.empty()) {
		throw std::runtime_error(too_big);
	}
	try {
		m_hash.assign(hash_size_for(m_options.max_blocks), TsdfHashEntry());
		m_hash_mask = uint32_t(m_hash.size()) - 1;
		// Address space for the whole cap at once, so that the pool never moves; pages are only
		// committed as blocks are first written.
		m_voxels.reserve(size_t(m_options.max_blocks) * TSDF_BLOCK_VOXELS);
	} catch (const std::bad_alloc &) { // an address-space limit (ulimit -v), or no overcommit
		char text[256];
		std::snprintf(text, sizeof(text), "max_blocks %d: the %.1f GiB its full model needs could not be reserved (out of memory or address space): lower max_blocks",
				m_options.max_blocks, double(tsdf_capacity_bytes(m_options.max_blocks)) / double(uint64_t(1) << 30));
		throw std::runtime_error(text);
	}
}

TsdfVolume::~TsdfVolume() = default;
TsdfVolume::TsdfVolume(TsdfVolume &&) noexcept = default;
TsdfVolume &TsdfVolume::operator=(TsdfVolume &&) noexcept = default;

// ---- where the pool lives ----

TsdfVoxel *TsdfVolume::pool() {
	return m_gpu ? m_gpu->pool() : m_voxels.data();
}

const TsdfVoxel *TsdfVolume::pool() const {
	return m_gpu ? m_gpu->pool() : m_voxels.data();
}

std::string TsdfVolume::set_compute(std::shared_ptr<ComputeDevice> p_device, size_t p_window_blocks) {
	if (!p_device) {
		leave_device();
		set_status(false, false, "", "");
		return "";
	}
	std::string error;
	std::unique_ptr<TsdfIntegratorGpu> gpu = TsdfIntegratorGpu::create(std::move(p_device), size_t(m_options.max_blocks), &error, p_window_blocks);
	if (!gpu) {
		leave_device();
		set_status(false, false, "integration on the GPU: " + error, "");
		return compute_problem();
	}
	const size_t used = m_slot_block.size() * TSDF_BLOCK_VOXELS;
	std::copy_n(pool(), used, gpu->pool());
	m_gpu_raycaster.reset();
	m_gpu = std::move(gpu);
	m_voxels = std::vector<TsdfVoxel>();
	m_gpu_raycaster = TsdfRaycasterGpu::create(*m_gpu, &error);
	set_status(true, bool(m_gpu_raycaster), "", m_gpu_raycaster ? "" : "the raycast on the GPU: " + error);
	return compute_problem();
}

void TsdfVolume::leave_device() {
	if (!m_gpu) {
		return;
	}
	m_gpu_raycaster.reset();
	const size_t used = m_slot_block.size() * TSDF_BLOCK_VOXELS;
	m_voxels.reserve(size_t(m_options.max_blocks) * TSDF_BLOCK_VOXELS); // as the constructor: the pool never moves
	m_voxels.assign(m_gpu->pool(), m_gpu->pool() + used);
	m_gpu.reset();
}

void TsdfVolume::set_status(bool p_integrating, bool p_raycasting, const std::string &p_integration_problem, const std::string &p_raycast_problem) const {
	const std::lock_guard<std::mutex> lock(m_status->mutex);
	m_status->integrating = p_integrating;
	m_status->raycasting = p_raycasting;
	m_status->integration_problem = p_integration_problem;
	m_status->raycast_problem = p_raycast_problem;
}

bool TsdfVolume::integrates_on_gpu() const {
	const std::lock_guard<std::mutex> lock(m_status->mutex);
	return m_status->integrating;
}

bool TsdfVolume::raycasts_on_gpu() const {
	const std::lock_guard<std::mutex> lock(m_status->mutex);
	return m_status->raycasting;
}

std::string TsdfVolume::compute_problem() const {
	const std::lock_guard<std::mutex> lock(m_status->mutex);
	const ComputeStatus &s = *m_status;
	std::string out = s.integration_problem.empty() ? "" : "integration on the CPU (" + s.integration_problem + ")";
	if (!s.raycast_problem.empty()) {
		out += std::string(out.empty() ? "" : "; ") + "raycasts on the CPU (" + s.raycast_problem + ")";
	}
	return out;
}

// ---- hash table ----

int32_t *TsdfVolume::hash_lookup(const glm::ivec3 &p_block) {
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY) {
		if (m_hash[i].block == p_block) {
			return &m_hash[i].slot;
		}
		i = (i + 1) & m_hash_mask;
	}
	return nullptr;
}

bool TsdfVolume::hash_insert(const glm::ivec3 &p_block, int32_t p_slot) {
	if (double(m_hash_used + 1) > MAX_HASH_LOAD * double(m_hash.size())) {
		return false;
	}
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY) {
		i = (i + 1) & m_hash_mask;
	}
	m_hash[i] = { p_block, p_slot };
	m_hash_used++;
	return true;
}

void TsdfVolume::hash_erase(const glm::ivec3 &p_block) {
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY && m_hash[i].block != p_block) {
		i = (i + 1) & m_hash_mask;
	}
	if (m_hash[i].slot == TSDF_HASH_EMPTY) {
		return;
	}
	// Backward-shift deletion: move later entries of the run into the hole when their home slot
	// does not lie (cyclically) between the hole and them, so that no probe sequence breaks.
	uint32_t hole = i;
	uint32_t j = i;
	for (;;) {
		j = (j + 1) & m_hash_mask;
		if (m_hash[j].slot == TSDF_HASH_EMPTY) {
			break;
		}
		const uint32_t home = tsdf_block_hash(m_hash[j].block) & m_hash_mask;
		const bool home_in_range = hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
		if (!home_in_range) {
			m_hash[hole] = m_hash[j];
			hole = j;
		}
	}
	m_hash[hole] = TsdfHashEntry();
	m_hash_used--;
}

// ---- pool ----

int32_t TsdfVolume::allocate_slot(const glm::ivec3 &p_block) {
	int32_t slot;
	if (!m_free_slots.empty()) {
		slot = m_free_slots.back();
		m_free_slots.pop_back();
		std::fill_n(pool() + ptrdiff_t(slot) * TSDF_BLOCK_VOXELS, TSDF_BLOCK_VOXELS, TsdfVoxel());
	} else {
		slot = int32_t(m_slot_block.size());
		m_slot_block.push_back(p_block);
		m_slot_used.push_back(0);
		m_slot_frame.push_back(0);
		m_slot_surface.push_back(TsdfSurfaceFrames());
		m_slot_saturated.push_back(0);
		if (m_gpu) {
			std::fill_n(pool() + ptrdiff_t(slot) * TSDF_BLOCK_VOXELS, TSDF_BLOCK_VOXELS, TsdfVoxel());
		} else {
			m_voxels.resize(m_voxels.size() + TSDF_BLOCK_VOXELS);
		}
	}
	m_slot_block[size_t(slot)] = p_block;
	m_slot_used[size_t(slot)] = 1;
	m_slot_frame[size_t(slot)] = m_frame;
	m_slot_surface[size_t(slot)] = TsdfSurfaceFrames();
	m_slot_surface[size_t(slot)].add(m_frame); // allocated only along a reading's band
	m_slot_saturated[size_t(slot)] = 0;
	m_allocated++;
	return slot;
}

void TsdfVolume::free_slot(int32_t p_slot) {
	m_slot_used[size_t(p_slot)] = 0;
	m_free_slots.push_back(p_slot);
	m_allocated--;
}

// ---- eviction ----

float TsdfVolume::keep_distance2(const glm::ivec3 &p_block, const Pose &p_world_from_camera) const {
	const glm::dvec3 c(block_centre(p_block, m_options.voxel_size_m));
	if (m_keep_points.empty()) {
		const glm::dvec3 d = c - p_world_from_camera.translation;
		return float(glm::dot(d, d));
	}
	double best = std::numeric_limits<double>::infinity();
	for (const glm::dvec3 &k : m_keep_points) {
		const glm::dvec3 d = c - k;
		best = std::min(best, glm::dot(d, d));
	}
	return float(best);
}

int TsdfVolume::evict_for(int p_needed, const Pose &p_world_from_camera) {
	std::vector<std::pair<float, int32_t>> candidates; // (-distance², slot): farthest first
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s] && m_slot_frame[s] != m_frame) {
			candidates.emplace_back(-keep_distance2(m_slot_block[s], p_world_from_camera), int32_t(s));
		}
	}
	const int count = std::min(p_needed, int(candidates.size()));
	std::nth_element(candidates.begin(), candidates.begin() + count, candidates.end());
	for (int i = 0; i < count; i++) {
		const int32_t slot = candidates[size_t(i)].second;
		hash_erase(m_slot_block[size_t(slot)]);
		m_dirty.push_back(m_slot_block[size_t(slot)]);
		free_slot(slot);
	}
	m_evicted_total += count;
	return count;
}

// ---- queries ----

TsdfView TsdfVolume::view() const {
	TsdfView view;
	view.entries = m_hash.data();
	view.mask = m_hash_mask;
	view.voxels = pool();
	view.voxel_size = m_options.voxel_size_m;
	view.truncation = m_options.truncation_m;
	return view;
}

const TsdfVoxel *TsdfVolume::find_block(const glm::ivec3 &p_block) const {
	const int32_t slot = tsdf_find_slot(view(), p_block);
	return slot >= 0 ? pool() + size_t(slot) * TSDF_BLOCK_VOXELS : nullptr;
}

glm::ivec3 TsdfVolume::block_at(const glm::vec3 &p_world) const {
	// The nearest voxel (voxel v's centre is at v x voxel_size_m), then its block (v >> 3: floor division).
	const glm::vec3 g = p_world / m_options.voxel_size_m;
	const glm::ivec3 voxel(tsdf_floor(g.x + 0.5f), tsdf_floor(g.y + 0.5f), tsdf_floor(g.z + 0.5f));
	return glm::ivec3(voxel.x >> 3, voxel.y >> 3, voxel.z >> 3);
}

TsdfSurfaceFrames TsdfVolume::surface_frames(const glm::ivec3 &p_block) const {
	const int32_t slot = tsdf_find_slot(view(), p_block);
	return slot >= 0 ? m_slot_surface[size_t(slot)] : TsdfSurfaceFrames();
}

namespace {
bool ivec3_less(const glm::ivec3 &p_a, const glm::ivec3 &p_b) {
	if (p_a.x != p_b.x) {
		return p_a.x < p_b.x;
	}
	if (p_a.y != p_b.y) {
		return p_a.y < p_b.y;
	}
	return p_a.z < p_b.z;
}
} // namespace

std::vector<glm::ivec3> TsdfVolume::allocated_blocks() const {
	std::vector<glm::ivec3> blocks;
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s]) {
			blocks.push_back(m_slot_block[s]);
		}
	}
	std::sort(blocks.begin(), blocks.end(), ivec3_less);
	return blocks;
}

std::vector<glm::ivec3> TsdfVolume::take_dirty_blocks() {
	std::vector<glm::ivec3> dirty;
	dirty.swap(m_dirty);
	std::sort(dirty.begin(), dirty.end(), ivec3_less);
	dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
	return dirty;
}

void TsdfVolume::set_keep_points(const std::vector<glm::dvec3> &p_points) {
	m_keep_points = p_points;
}

void TsdfVolume::reset() {
	for (const glm::ivec3 &block : allocated_blocks()) {
		m_dirty.push_back(block);
	}
	std::fill(m_hash.begin(), m_hash.end(), TsdfHashEntry());
	m_hash_used = 0;
	m_hash_version++;
	m_voxels.clear();
	m_slot_block.clear();
	m_slot_used.clear();
	m_slot_frame.clear();
	m_slot_surface.clear();
	m_slot_saturated.clear();
	m_free_slots.clear();
	m_allocated = 0;
	m_bounds_min = m_bounds_max = glm::vec3(0.0f);
}

TsdfStats TsdfVolume::stats() const {
	TsdfStats stats;
	stats.allocated_blocks = m_allocated;
	stats.capacity_blocks = m_options.max_blocks;
	const size_t block_bytes = sizeof(TsdfVoxel) * TSDF_BLOCK_VOXELS + sizeof(glm::ivec3) + 2 * sizeof(uint32_t);
	const size_t hash_bytes = m_hash.size() * sizeof(TsdfHashEntry);
	stats.bytes_used = size_t(m_allocated) * block_bytes + hash_bytes;
	// The device's pool is held whole (tsdf_integrate_gpu.h).
	stats.bytes_reserved = (m_gpu ? m_gpu->pool_blocks() : m_slot_block.size()) * block_bytes + hash_bytes;
	stats.evicted_blocks_total = m_evicted_total;
	stats.dropped_blocks_total = m_dropped_total;
	stats.bounds_min = m_bounds_min;
	stats.bounds_max = m_bounds_max;
	return stats;
}

} // namespace roomprobe
