#pragma once
// Triangle meshes of the TSDF's zero level set by marching cubes (tsdf_volume.h), kept per block
// so that only the blocks a frame changed are re-meshed.

#include "slam/tsdf_volume.h"

#include <glm/vec3.hpp>
#include <glm/gtc/type_precision.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <tuple>
#include <vector>

namespace roomprobe {

struct TriangleMesh {
	std::vector<glm::vec3> vertices; // world metres
	std::vector<glm::vec3> normals; // world, unit, pointing out of the surface (towards free space)
	std::vector<glm::u8vec3> colors; // R, G, B
	std::vector<uint32_t> indices; // triangles, counter-clockwise seen from the free side
};

// The marching-cubes case table: for each of the 256 sign patterns of a cube's corners (bit c
// set when corner c, at (c & 1, c >> 1 & 1, c >> 2 & 1), is inside, tsdf < 0), the triangles as
// triples of cube edges (edge e joins mc_edge_corners()[e]). Generated at first use from the
// cube's topology (marching_cubes.cpp): contours are traced face by face, separating the inside
// corners on ambiguous faces, so that neighbouring cubes always agree (watertight).
struct McCase {
	uint8_t triangle_count = 0;
	std::array<uint8_t, 3 * 12> edges {}; // triangle_count triples
};
const std::array<McCase, 256> &mc_case_table();
const std::array<std::array<uint8_t, 2>, 12> &mc_edge_corners();

// The voxels that re-meshing a set of changed blocks reads, copied out of a volume at one
// moment: the changed blocks and every allocated block next to them (a cube reads one voxel into
// the blocks above it, and the blocks below a changed one are re-meshed too). A mesher works on
// the copy on its own thread while the volume goes on fusing frames.
class TsdfBlockCopy {
public:
	TsdfBlockCopy() = default;
	// p_changed_blocks: sorted, each once (TsdfVolume::take_dirty_blocks). p_storage: the voxel
	// storage of an earlier copy to reuse (release_storage), or empty.
	TsdfBlockCopy(const TsdfVolume &p_volume, std::vector<glm::ivec3> p_changed_blocks, std::vector<TsdfVoxel> p_storage = {});
	// Gives the voxel storage back for the next copy (this copy is empty afterwards).
	std::vector<TsdfVoxel> release_storage() {
		m_keys.clear();
		m_changed.clear();
		return std::move(m_voxels);
	}
	// The 512 voxels of a copied block, or nullptr (not allocated, or not near a changed block).
	const TsdfVoxel *find_block(const glm::ivec3 &p_block) const;
	const std::vector<glm::ivec3> &changed_blocks() const { return m_changed; }
	float voxel_size_m() const { return m_voxel_size_m; }
	size_t block_count() const { return m_voxels.size() / TSDF_BLOCK_VOXELS; }

private:
	float m_voxel_size_m = 0.01f;
	std::vector<glm::ivec3> m_changed;
	std::vector<uint64_t> m_keys; // packed block keys, sorted: block i's voxels are m_voxels[512 i ...]
	std::vector<TsdfVoxel> m_voxels;
};

// The mesh of the cubes whose lowest corner lies in one block (they reach one voxel into the
// blocks above it). Cubes with an unobserved corner, or whose sign change is between two
// saturated (+-1) values, give nothing.
TriangleMesh mesh_block(const TsdfVolume &p_volume, const glm::ivec3 &p_block);
TriangleMesh mesh_block(const TsdfBlockCopy &p_blocks, const glm::ivec3 &p_block);
// The mesh of the whole volume from scratch (blocks in sorted order), as IncrementalMesher::mesh().
TriangleMesh mesh_volume(const TsdfVolume &p_volume);

// Appends p_piece to r_mesh (indices shifted).
void append_mesh(const TriangleMesh &p_piece, TriangleMesh *r_mesh);

// Orders block and region indices (std::map keys).
struct IvecLess {
	bool operator()(const glm::ivec3 &p_a, const glm::ivec3 &p_b) const {
		return std::tie(p_a.x, p_a.y, p_a.z) < std::tie(p_b.x, p_b.y, p_b.z);
	}
};

// Keeps one mesh piece per block and re-meshes only what changed.
class IncrementalMesher {
public:
	// Re-meshes the blocks whose cubes touch a changed block: each changed block and its 7
	// neighbours below (-x, -y, -z and combinations), whose cubes reach into it. Pieces of blocks
	// that are no longer allocated are dropped. Returns the number of blocks meshed.
	int update(const TsdfBlockCopy &p_blocks);
	// The same, copying from p_volume first.
	int update(const TsdfVolume &p_volume, const std::vector<glm::ivec3> &p_changed_blocks);
	// The whole mesh: the pieces concatenated in sorted block order.
	TriangleMesh mesh() const;
	// The mesh of each region of p_region_blocks^3 blocks (key: block index floor-divided by
	// p_region_blocks) in p_regions, in one pass; a region with no triangles maps to an empty mesh.
	// Lets a viewer replace only the regions that changed.
	std::map<glm::ivec3, TriangleMesh, struct IvecLess> region_meshes(int p_region_blocks, const std::vector<glm::ivec3> &p_regions) const;
	// The regions whose meshes the last update() changed (the changed blocks and the neighbours
	// it re-meshed), for p_region_blocks.
	std::vector<glm::ivec3> changed_regions(int p_region_blocks) const;
	void clear() {
		m_pieces.clear();
		m_last_touched.clear();
	}
	size_t piece_count() const { return m_pieces.size(); }

private:
	struct BlockLess {
		bool operator()(const glm::ivec3 &p_a, const glm::ivec3 &p_b) const {
			return std::tie(p_a.x, p_a.y, p_a.z) < std::tie(p_b.x, p_b.y, p_b.z);
		}
	};
	std::map<glm::ivec3, TriangleMesh, BlockLess> m_pieces;
	std::vector<glm::ivec3> m_last_touched; // blocks re-meshed (or dropped) by the last update()
};

} // namespace roomprobe
