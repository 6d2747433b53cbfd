#pragma once
// The engine's mesh stage: the dense model's mesh, re-meshed from copies of the blocks that
// changed (slam/marching_cubes.h, TsdfBlockCopy), so that marching cubes run on the mesh worker
// while the SLAM worker fuses on. The snapshots it returns are immutable.

#include <slam/dense_slam.h>
#include <slam/marching_cubes.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

namespace roomprobe {

// The dense mesh, whole (placement, scripts) and cut into cubic regions (display): a viewer
// replaces only the regions whose version changed, so a growing model costs the main thread
// what changed, not the whole mesh.
struct DenseMeshChunk {
	glm::ivec3 region = glm::ivec3(0); // block index / DENSE_MESH_REGION_BLOCKS
	uint64_t version = 0; // changes whenever this region's triangles do
	std::shared_ptr<const TriangleMesh> mesh; // world metres; never empty
};

inline constexpr int DENSE_MESH_REGION_BLOCKS = 8; // 8 blocks of 8 voxels: 64 cm at 1 cm voxels

struct DenseMeshSnapshot {
	uint64_t version = 0;
	std::shared_ptr<const TriangleMesh> mesh; // the whole mesh, world metres
	std::vector<DenseMeshChunk> chunks; // every non-empty region
	// What making it cost: copying the changed blocks on the SLAM thread, and marching cubes plus
	// the whole mesh and the regions on the mesh worker (both on the caller in step mode).
	double copy_ms = 0.0;
	double mesh_ms = 0.0;
	size_t copied_blocks = 0;
};

class DenseMeshStage {
public:
	// The changed blocks, copied on the fusing thread: the mesh worker's input.
	struct Input {
		TsdfBlockCopy blocks;
		double copy_ms = 0.0;
	};

	// On the thread that fuses p_slam: the blocks changed since the last copy (the storage of
	// the last copy meshed is reused: its pages stay mapped).
	std::shared_ptr<Input> copy_changed(DenseSlam &p_slam);
	// On any one thread at a time (the mesh worker, or the caller when stopped): meshes p_input,
	// gives its storage back, and returns the mesh (version 0: the engine numbers what it
	// publishes); r_changed: whether the whole mesh changed (a new placement scene is due).
	std::shared_ptr<DenseMeshSnapshot> mesh(Input &p_input, bool *r_changed);
	// Forgets the model's mesh (a new configuration).
	void clear();

private:
	std::mutex mutex; // the mesher and the chunks: held while meshing
	IncrementalMesher mesher;
	std::shared_ptr<const TriangleMesh> whole;
	std::map<glm::ivec3, DenseMeshChunk, IvecLess> chunks;
	uint64_t chunk_versions = 0;
	// The last copy's storage, for the next one: its own lock, so that the fusing thread never
	// waits for a meshing.
	std::mutex spare_mutex;
	std::vector<TsdfVoxel> spare_storage;
};

} // namespace roomprobe
