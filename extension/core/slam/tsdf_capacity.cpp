#include "tsdf_capacity.h"

#include "slam/tsdf_kernels.h"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace roomprobe {

namespace {

// As TsdfVolume counts a block (TsdfVolume::stats): its voxels, its coordinates, and two words of
// bookkeeping.
constexpr uint64_t BLOCK_BYTES = sizeof(TsdfVoxel) * TSDF_BLOCK_VOXELS + sizeof(glm::ivec3) + 2 * sizeof(uint32_t);
// The largest cap TsdfVolume takes (it clamps max_blocks to [1, 1 << 22]).
constexpr int MAX_BLOCKS = 1 << 22;

// The hash table's slots, as TsdfVolume sizes it (tsdf_volume.cpp, hash_size_for): the least power of
// two from 1024 that keeps 1.5 times the cap at most 3/4 full. test_slam_tsdf.cpp checks the two agree.
uint64_t hash_slots(int p_max_blocks) {
	uint64_t size = 1024;
	while (double(size) * 0.75 < 1.5 * double(p_max_blocks)) {
		size *= 2;
	}
	return size;
}

double gib(uint64_t p_bytes) {
	return double(p_bytes) / double(uint64_t(1) << 30);
}

} // namespace

uint64_t tsdf_capacity_bytes(int p_max_blocks) {
	const int blocks = std::clamp(p_max_blocks, 1, MAX_BLOCKS);
	return uint64_t(blocks) * BLOCK_BYTES + hash_slots(blocks) * sizeof(TsdfHashEntry);
}

uint64_t physical_memory_bytes() {
	const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
	return pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
}

std::string tsdf_capacity_problem(const std::string &p_option, int p_max_blocks, uint64_t p_memory_bytes) {
	const uint64_t needed = tsdf_capacity_bytes(p_max_blocks);
	if (p_memory_bytes == 0 || needed <= p_memory_bytes) {
		return "";
	}
	// The most blocks that fit (the hash table grows in steps, so searched).
	int low = 0, high = std::clamp(p_max_blocks, 1, MAX_BLOCKS);
	while (low < high) {
		const int mid = low + (high - low + 1) / 2;
		if (tsdf_capacity_bytes(mid) <= p_memory_bytes) {
			low = mid;
		} else {
			high = mid - 1;
		}
	}
	char text[384];
	std::snprintf(text, sizeof(text),
			"%s %d needs %.1f GiB of memory when the model is full (%llu bytes a block, and a %.0f MiB hash table), more than this "
			"machine's %.1f GiB: give at most %d",
			p_option.c_str(), p_max_blocks, gib(needed), (unsigned long long)BLOCK_BYTES,
			double(hash_slots(std::clamp(p_max_blocks, 1, MAX_BLOCKS)) * sizeof(TsdfHashEntry)) / double(1 << 20), gib(p_memory_bytes), low);
	return text;
}

} // namespace roomprobe
