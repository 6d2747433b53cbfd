// The TSDF's cap on blocks against the machine's memory (issue #38): max_blocks at the top of its
// range (4194304 blocks, 24 GiB) ended in a bare std::bad_alloc when the volume was made. A cap the
// machine cannot hold is refused, naming the option, the memory it needs and the most that fits.

#include "slam/tsdf_capacity.h"
#include "slam/tsdf_volume.h"
#include "slam_test_scenes.h"

#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <sys/resource.h>
#include <unistd.h>

using namespace roomprobe;
using namespace slam_test;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// What TsdfVolume's constructor says, or "" when it makes the volume.
std::string construction_error(int p_max_blocks) {
	TsdfOptions options;
	options.max_blocks = p_max_blocks;
	try {
		const TsdfVolume volume(options);
	} catch (const std::exception &e) {
		return e.what();
	}
	return "";
}

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool SANITIZED = true; // the sanitizers reserve terabytes of shadow: no address-space limit
#else
constexpr bool SANITIZED = false;
#endif

// This process's address space now, bytes (/proc/self/statm's first field, in pages).
uint64_t address_space_bytes() {
	std::ifstream statm("/proc/self/statm");
	uint64_t pages = 0;
	statm >> pages;
	return pages * uint64_t(::sysconf(_SC_PAGESIZE));
}

} // namespace

TEST_CASE("TSDF capacity: the bytes a full volume holds agree with the volume's own count") {
	// TsdfStats::bytes_used = allocated blocks x their bytes + the hash table; a full volume's is
	// tsdf_capacity_bytes. Checked on volumes with blocks allocated, so that both parts are tested.
	const uint64_t block_bytes = sizeof(TsdfVoxel) * TSDF_BLOCK_VOXELS + sizeof(glm::ivec3) + 2 * sizeof(uint32_t);
	const PinholeIntrinsics camera = rig_camera(2);
	Scene scene;
	scene.spheres.push_back({ glm::dvec3(0.0, 0.0, 0.0), 0.3 });
	const Frame frame = render(scene, camera, orbit_pose(glm::dvec3(0.0), 1.0, 0.0, 0.0));
	for (int cap : { 1, 700, 900, 40000, 200000 }) {
		TsdfOptions options;
		options.max_blocks = cap;
		TsdfVolume volume(options);
		volume.integrate(frame.depth, frame.rgb, camera, frame.world_from_camera);
		const TsdfStats stats = volume.stats();
		REQUIRE(stats.allocated_blocks > 0);
		CAPTURE(cap);
		CHECK(stats.bytes_used - uint64_t(stats.allocated_blocks) * block_bytes == tsdf_capacity_bytes(cap) - uint64_t(cap) * block_bytes);
	}
	CHECK(tsdf_capacity_bytes(4194304) == 4194304ull * block_bytes + (uint64_t(1) << 23) * sizeof(TsdfHashEntry));
	CHECK(physical_memory_bytes() > 0);
}

TEST_CASE("TSDF capacity: a cap beyond the machine's memory is refused, naming the option, the memory and the most that fits") {
	const uint64_t memory = uint64_t(23) << 30; // a machine of 23 GiB, as the one that gave std::bad_alloc
	const std::string problem = tsdf_capacity_problem("DenseSLAM.max_blocks", 4194304, memory);
	CHECK(contains(problem, "DenseSLAM.max_blocks 4194304 needs 24.2 GiB of memory when the model is full"));
	CHECK(contains(problem, "more than this machine's 23.0 GiB"));
	const size_t at = problem.find("give at most ");
	REQUIRE(at != std::string::npos);
	const int most = std::stoi(problem.substr(at + 13));
	CHECK(tsdf_capacity_bytes(most) <= memory);
	CHECK(tsdf_capacity_bytes(most + 1) > memory);
	CHECK(tsdf_capacity_problem("max_blocks", most, memory).empty());
	CHECK_FALSE(tsdf_capacity_problem("max_blocks", most + 1, memory).empty());
	CHECK(tsdf_capacity_problem("max_blocks", 40000, memory).empty()); // the default: 0.2 GiB
	CHECK(tsdf_capacity_problem("max_blocks", 4194304, 0).empty()); // memory unknown: not refused here

	// The volume itself: at the top of the range it is refused by this check where the machine is
	// smaller than 24.2 GiB, and made where it is larger.
	const std::string top = construction_error(4194304);
	if (physical_memory_bytes() < tsdf_capacity_bytes(4194304)) {
		CHECK(contains(top, "max_blocks 4194304 needs 24.2 GiB of memory"));
		CHECK_FALSE(contains(top, "bad_alloc"));
	} else {
		CHECK(top.empty());
	}
}

TEST_CASE("TSDF capacity: a cap whose address space cannot be reserved is an error naming max_blocks, not std::bad_alloc" *
		doctest::skip(SANITIZED)) {
	// An address-space limit (ulimit -v) 1 GiB above what the process holds: the 5.7 GiB a cap of
	// 1000000 blocks reserves cannot be had, whatever the machine's memory. No check runs while the
	// limit holds.
	rlimit saved{};
	REQUIRE(::getrlimit(RLIMIT_AS, &saved) == 0);
	rlimit limit = saved;
	limit.rlim_cur = address_space_bytes() + (uint64_t(1) << 30);
	if (saved.rlim_cur != RLIM_INFINITY && saved.rlim_cur < limit.rlim_cur) {
		limit.rlim_cur = saved.rlim_cur;
	}
	std::string error;
	if (::setrlimit(RLIMIT_AS, &limit) == 0) {
		error = construction_error(1000000);
		::setrlimit(RLIMIT_AS, &saved);
	}
	CHECK(contains(error, "max_blocks 1000000"));
	CHECK_FALSE(contains(error, "bad_alloc"));
	CHECK(construction_error(1000).empty()); // and the limit is gone
}
