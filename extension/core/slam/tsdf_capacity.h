#pragma once
// What a TsdfVolume's cap on blocks (TsdfOptions::max_blocks) costs in memory, and whether this
// machine has it (issue #38). The volume reserves address space for the whole cap when it is made,
// so that its voxel pool never moves: max_blocks at the top of its range (4194304 blocks, 24 GiB)
// once ended in a bare std::bad_alloc. A cap the machine cannot hold is now refused, naming the
// option, the memory it needs and the most that fits.

#include <cstdint>
#include <string>

namespace roomprobe {

// Bytes a volume capped at p_max_blocks holds when every block is allocated: each block's voxels
// and bookkeeping (TsdfStats::bytes_used's count), and the hash table sized for the cap.
uint64_t tsdf_capacity_bytes(int p_max_blocks);

// This machine's physical memory, bytes; 0 when it cannot be told.
uint64_t physical_memory_bytes();

// "" when a cap of p_max_blocks blocks fits in p_memory_bytes (0: unknown, taken as fitting);
// otherwise, naming p_option ("max_blocks", "DenseSLAM.max_blocks"): "DenseSLAM.max_blocks 4194304
// needs 24.1 GiB of memory when the model is full (...), more than this machine's 23.4 GiB: give
// at most 3890000".
std::string tsdf_capacity_problem(const std::string &p_option, int p_max_blocks, uint64_t p_memory_bytes);

} // namespace roomprobe
