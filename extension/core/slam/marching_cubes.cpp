#include "marching_cubes.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace roomprobe {

namespace {

glm::ivec3 corner_offset(int p_corner) {
	return { p_corner & 1, (p_corner >> 1) & 1, (p_corner >> 2) & 1 };
}

struct CubeTopology {
	std::array<std::array<uint8_t, 2>, 12> edge_corners {}; // lower corner first
	std::array<std::array<int8_t, 8>, 8> edge_of {}; // corner pair -> edge, -1 when not an edge
	std::array<std::array<uint8_t, 4>, 6> faces {}; // corners, counter-clockwise seen from outside
};

CubeTopology make_topology() {
	CubeTopology topology;
	for (auto &row : topology.edge_of) {
		row.fill(-1);
	}
	int e = 0;
	for (int axis = 0; axis < 3; axis++) {
		for (int c = 0; c < 8; c++) {
			if (!(c & (1 << axis))) {
				const int d = c | (1 << axis);
				topology.edge_corners[size_t(e)] = { uint8_t(c), uint8_t(d) };
				topology.edge_of[size_t(c)][size_t(d)] = topology.edge_of[size_t(d)][size_t(c)] = int8_t(e);
				e++;
			}
		}
	}
	// Face normal +-axis; with u, v the next axes (e_u x e_v = e_axis), (0,0) (1,0) (1,1) (0,1)
	// is counter-clockwise seen from the + side; the - side takes it backwards.
	const int square[4][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 } };
	int f = 0;
	for (int axis = 0; axis < 3; axis++) {
		const int u = (axis + 1) % 3, v = (axis + 2) % 3;
		for (int side = 0; side < 2; side++) {
			for (int i = 0; i < 4; i++) {
				const int k = side == 1 ? i : 3 - i;
				const int corner = (side << axis) | (square[k][0] << u) | (square[k][1] << v);
				topology.faces[size_t(f)][size_t(i)] = uint8_t(corner);
			}
			f++;
		}
	}
	return topology;
}

const CubeTopology &topology() {
	static const CubeTopology t = make_topology();
	return t;
}

// One case: on each face, the contour leaves the face's boundary where it passes from an outside
// to an inside corner (counter-clockwise seen from outside) and is joined to the next crossing
// from inside to outside, which cuts off the inside corners between them; on an ambiguous face
// (two diagonal inside corners) this separates them, and since a face's choice depends on its own
// corners only, the two cubes sharing it agree. Each crossed edge is left by exactly one segment
// (the two faces meeting there run along it in opposite directions), so the segments form loops;
// the inside lies to their right seen from outside, so the fan of each loop faces the outside.
McCase make_case(int p_mask) {
	const CubeTopology &t = topology();
	std::array<int8_t, 12> next;
	next.fill(-1);
	auto inside = [p_mask](int p_corner) { return (p_mask >> p_corner) & 1; };
	for (const auto &face : t.faces) {
		for (int i = 0; i < 4; i++) {
			const int a = face[size_t(i)], b = face[size_t((i + 1) % 4)];
			if (inside(a) || !inside(b)) {
				continue; // not an outside -> inside crossing
			}
			for (int k = 1; k < 4; k++) {
				const int c = face[size_t((i + k) % 4)], d = face[size_t((i + k + 1) % 4)];
				if (inside(c) && !inside(d)) {
					next[size_t(t.edge_of[size_t(a)][size_t(b)])] = t.edge_of[size_t(c)][size_t(d)];
					break;
				}
			}
		}
	}
	McCase result;
	std::array<bool, 12> used {};
	for (int start = 0; start < 12; start++) {
		if (next[size_t(start)] < 0 || used[size_t(start)]) {
			continue;
		}
		std::vector<int> loop;
		for (int e = start; !used[size_t(e)]; e = next[size_t(e)]) {
			used[size_t(e)] = true;
			loop.push_back(e);
		}
		for (size_t i = 1; i + 1 < loop.size(); i++) {
			const size_t o = size_t(result.triangle_count) * 3;
			result.edges[o] = uint8_t(loop[0]);
			result.edges[o + 1] = uint8_t(loop[i]);
			result.edges[o + 2] = uint8_t(loop[i + 1]);
			result.triangle_count++;
		}
	}
	return result;
}

std::array<McCase, 256> make_case_table() {
	std::array<McCase, 256> table;
	for (int mask = 0; mask < 256; mask++) {
		table[size_t(mask)] = make_case(mask);
	}
	return table;
}

// The voxels a block's cubes read: the block and one layer of the blocks above it.
constexpr int GRID = TSDF_BLOCK_SIDE + 1;

struct BlockNeighbourhood {
	std::array<const TsdfVoxel *, GRID * GRID * GRID> voxels {};
	const TsdfVoxel *at(const glm::ivec3 &p_local) const { return voxels[size_t((p_local.z * GRID + p_local.y) * GRID + p_local.x)]; }
};

// p_blocks: a TsdfVolume or a TsdfBlockCopy (find_block).
template <typename Blocks>
BlockNeighbourhood gather(const Blocks &p_blocks, const glm::ivec3 &p_block) {
	BlockNeighbourhood n;
	const TsdfVoxel *blocks[8];
	for (int c = 0; c < 8; c++) {
		blocks[c] = p_blocks.find_block(p_block + corner_offset(c));
	}
	for (int z = 0; z < GRID; z++) {
		for (int y = 0; y < GRID; y++) {
			for (int x = 0; x < GRID; x++) {
				const int bx = x / TSDF_BLOCK_SIDE, by = y / TSDF_BLOCK_SIDE, bz = z / TSDF_BLOCK_SIDE;
				const TsdfVoxel *block = blocks[bx | (by << 1) | (bz << 2)];
				const glm::ivec3 local(x % TSDF_BLOCK_SIDE, y % TSDF_BLOCK_SIDE, z % TSDF_BLOCK_SIDE);
				n.voxels[size_t((z * GRID + y) * GRID + x)] = block != nullptr ? &block[tsdf_local_index(local)] : nullptr;
			}
		}
	}
	return n;
}

// The gradient of the cube's trilinear tsdf at local position p_f in [0, 1]^3.
glm::vec3 cube_gradient(const std::array<float, 8> &p_f, const glm::vec3 &p_frac) {
	glm::vec3 g(0.0f);
	for (int i = 0; i < 8; i++) {
		const glm::ivec3 o = corner_offset(i);
		const float wx = o.x ? p_frac.x : 1.0f - p_frac.x, wy = o.y ? p_frac.y : 1.0f - p_frac.y, wz = o.z ? p_frac.z : 1.0f - p_frac.z;
		g.x += p_f[size_t(i)] * (o.x ? 1.0f : -1.0f) * wy * wz;
		g.y += p_f[size_t(i)] * (o.y ? 1.0f : -1.0f) * wx * wz;
		g.z += p_f[size_t(i)] * (o.z ? 1.0f : -1.0f) * wx * wy;
	}
	return g;
}

glm::u8vec3 edge_color(const TsdfVoxel &p_a, const TsdfVoxel &p_b, float p_t) {
	if (p_a.color_weight == 0 && p_b.color_weight == 0) {
		return glm::u8vec3(0);
	}
	const float t = p_a.color_weight == 0 ? 1.0f : (p_b.color_weight == 0 ? 0.0f : p_t);
	const glm::vec3 c = glm::mix(glm::vec3(p_a.r, p_a.g, p_a.b), glm::vec3(p_b.r, p_b.g, p_b.b), t);
	return glm::u8vec3(glm::round(c));
}

} // namespace

const std::array<McCase, 256> &mc_case_table() {
	static const std::array<McCase, 256> table = make_case_table();
	return table;
}

const std::array<std::array<uint8_t, 2>, 12> &mc_edge_corners() {
	return topology().edge_corners;
}

namespace {

template <typename Blocks>
TriangleMesh mesh_block_of(const Blocks &p_blocks, const glm::ivec3 &p_block, float p_voxel_size_m) {
	TriangleMesh mesh;
	if (p_blocks.find_block(p_block) == nullptr) {
		return mesh;
	}
	const BlockNeighbourhood n = gather(p_blocks, p_block);
	const std::array<McCase, 256> &table = mc_case_table();
	const CubeTopology &t = topology();
	const float vs = p_voxel_size_m;
	const glm::ivec3 base = p_block * TSDF_BLOCK_SIDE;
	// A vertex per crossed grid edge, shared by the cubes around it: (start voxel, axis).
	std::vector<int32_t> vertex_of(size_t(GRID * GRID * GRID * 3), -1);
	for (int z = 0; z < TSDF_BLOCK_SIDE; z++) {
		for (int y = 0; y < TSDF_BLOCK_SIDE; y++) {
			for (int x = 0; x < TSDF_BLOCK_SIDE; x++) {
				const glm::ivec3 cube(x, y, z);
				const TsdfVoxel *corners[8];
				std::array<float, 8> f;
				int mask = 0;
				bool ok = true;
				for (int c = 0; c < 8 && ok; c++) {
					corners[c] = n.at(cube + corner_offset(c));
					ok = corners[c] != nullptr && corners[c]->weight > 0;
					if (ok) {
						f[size_t(c)] = corners[c]->tsdf;
						mask |= (f[size_t(c)] < 0.0f) << c;
					}
				}
				if (!ok || mask == 0 || mask == 255) {
					continue;
				}
				// A sign change between two saturated values is a truncation artefact (the
				// boundary between seen free space and hidden space), not a surface.
				bool saturated = false;
				for (const auto &edge : t.edge_corners) {
					const float a = f[edge[0]], b = f[edge[1]];
					saturated |= ((a < 0.0f) != (b < 0.0f)) && std::fabs(a) >= 1.0f && std::fabs(b) >= 1.0f;
				}
				if (saturated) {
					continue;
				}
				const McCase &mc = table[size_t(mask)];
				for (int k = 0; k < 3 * mc.triangle_count; k++) {
					const int e = mc.edges[size_t(k)];
					const int ca = t.edge_corners[size_t(e)][0], cb = t.edge_corners[size_t(e)][1];
					const glm::ivec3 start = cube + corner_offset(ca);
					const int axis = e / 4; // edges are numbered axis by axis, 4 each
					int32_t &vertex = vertex_of[size_t(((start.z * GRID + start.y) * GRID + start.x) * 3 + axis)];
					if (vertex < 0) {
						const float s = f[size_t(ca)] / (f[size_t(ca)] - f[size_t(cb)]);
						glm::vec3 frac = glm::vec3(corner_offset(ca));
						frac[axis] = s;
						glm::vec3 local = glm::vec3(start);
						local[axis] += s;
						const glm::vec3 g = cube_gradient(f, frac);
						const float len = glm::length(g);
						vertex = int32_t(mesh.vertices.size());
						mesh.vertices.push_back((glm::vec3(base) + local) * vs);
						mesh.normals.push_back(len > 0.0f ? g / len : glm::vec3(0.0f));
						mesh.colors.push_back(edge_color(*corners[ca], *corners[cb], s));
					}
					mesh.indices.push_back(uint32_t(vertex));
				}
			}
		}
	}
	return mesh;
}

} // namespace

TriangleMesh mesh_block(const TsdfVolume &p_volume, const glm::ivec3 &p_block) {
	return mesh_block_of(p_volume, p_block, p_volume.options().voxel_size_m);
}

TriangleMesh mesh_block(const TsdfBlockCopy &p_blocks, const glm::ivec3 &p_block) {
	return mesh_block_of(p_blocks, p_block, p_blocks.voxel_size_m());
}

// ---- the copy a mesher works on ----

TsdfBlockCopy::TsdfBlockCopy(const TsdfVolume &p_volume, std::vector<glm::ivec3> p_changed_blocks, std::vector<TsdfVoxel> p_storage) :
		m_voxel_size_m(p_volume.options().voxel_size_m), m_changed(std::move(p_changed_blocks)), m_voxels(std::move(p_storage)) {
	// The blocks within one block of a changed one, each once (a bit per pool slot).
	const TsdfView view = p_volume.view();
	std::vector<uint64_t> taken((size_t(p_volume.stats().capacity_blocks) + 63) / 64, 0);
	std::vector<std::pair<uint64_t, int32_t>> found; // (block key, slot)
	found.reserve(m_changed.size() * 2);
	for (const glm::ivec3 &block : m_changed) {
		for (int dz = -1; dz <= 1; dz++) {
			for (int dy = -1; dy <= 1; dy++) {
				for (int dx = -1; dx <= 1; dx++) {
					const glm::ivec3 b = block + glm::ivec3(dx, dy, dz);
					const int32_t slot = tsdf_find_slot(view, b);
					if (slot >= 0 && !(taken[size_t(slot) / 64] >> (slot % 64) & 1u)) {
						taken[size_t(slot) / 64] |= uint64_t(1) << (slot % 64);
						found.emplace_back(tsdf_block_key(b), slot);
					}
				}
			}
		}
	}
	std::sort(found.begin(), found.end());
	// Appended, not resized: no voxel is written twice. Storage recycled from an earlier copy
	// keeps its pages (tens of megabytes: page faults on fresh memory cost as much as copying),
	// so it is reserved with room to grow.
	const size_t needed = found.size() * TSDF_BLOCK_VOXELS;
	m_voxels.clear();
	if (m_voxels.capacity() < needed) {
		m_voxels = std::vector<TsdfVoxel>();
		m_voxels.reserve(needed + needed / 4);
	}
	m_keys.reserve(found.size());
	for (const auto &[key, slot] : found) {
		m_keys.push_back(key);
		const TsdfVoxel *voxels = view.voxels + size_t(slot) * TSDF_BLOCK_VOXELS;
		m_voxels.insert(m_voxels.end(), voxels, voxels + TSDF_BLOCK_VOXELS);
	}
}

const TsdfVoxel *TsdfBlockCopy::find_block(const glm::ivec3 &p_block) const {
	const uint64_t key = tsdf_block_key(p_block);
	const auto it = std::lower_bound(m_keys.begin(), m_keys.end(), key);
	if (it == m_keys.end() || *it != key) {
		return nullptr;
	}
	return &m_voxels[size_t(it - m_keys.begin()) * TSDF_BLOCK_VOXELS];
}

void append_mesh(const TriangleMesh &p_piece, TriangleMesh *r_mesh) {
	const uint32_t offset = uint32_t(r_mesh->vertices.size());
	r_mesh->vertices.insert(r_mesh->vertices.end(), p_piece.vertices.begin(), p_piece.vertices.end());
	r_mesh->normals.insert(r_mesh->normals.end(), p_piece.normals.begin(), p_piece.normals.end());
	r_mesh->colors.insert(r_mesh->colors.end(), p_piece.colors.begin(), p_piece.colors.end());
	for (uint32_t i : p_piece.indices) {
		r_mesh->indices.push_back(i + offset);
	}
}

TriangleMesh mesh_volume(const TsdfVolume &p_volume) {
	TriangleMesh mesh;
	for (const glm::ivec3 &block : p_volume.allocated_blocks()) {
		append_mesh(mesh_block(p_volume, block), &mesh);
	}
	return mesh;
}

int IncrementalMesher::update(const TsdfVolume &p_volume, const std::vector<glm::ivec3> &p_changed_blocks) {
	return update(TsdfBlockCopy(p_volume, p_changed_blocks));
}

int IncrementalMesher::update(const TsdfBlockCopy &p_blocks) {
	std::vector<glm::ivec3> affected;
	affected.reserve(p_blocks.changed_blocks().size() * 8);
	for (const glm::ivec3 &block : p_blocks.changed_blocks()) {
		for (int c = 0; c < 8; c++) {
			affected.push_back(block - corner_offset(c));
		}
	}
	const BlockLess less;
	std::sort(affected.begin(), affected.end(), less);
	affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
	m_last_touched = affected;
	int meshed = 0;
	for (const glm::ivec3 &block : affected) {
		if (p_blocks.find_block(block) == nullptr) {
			m_pieces.erase(block);
			continue;
		}
		TriangleMesh piece = mesh_block(p_blocks, block);
		meshed++;
		if (piece.indices.empty()) {
			m_pieces.erase(block);
		} else {
			m_pieces[block] = std::move(piece);
		}
	}
	return meshed;
}

namespace {

int floor_div(int p_a, int p_b) {
	return p_a >= 0 ? p_a / p_b : -((-p_a + p_b - 1) / p_b);
}

glm::ivec3 region_of(const glm::ivec3 &p_block, int p_region_blocks) {
	return glm::ivec3(floor_div(p_block.x, p_region_blocks), floor_div(p_block.y, p_region_blocks), floor_div(p_block.z, p_region_blocks));
}

} // namespace

std::vector<glm::ivec3> IncrementalMesher::changed_regions(int p_region_blocks) const {
	std::vector<glm::ivec3> regions;
	for (const glm::ivec3 &block : m_last_touched) {
		regions.push_back(region_of(block, p_region_blocks));
	}
	const IvecLess less;
	std::sort(regions.begin(), regions.end(), less);
	regions.erase(std::unique(regions.begin(), regions.end()), regions.end());
	return regions;
}

std::map<glm::ivec3, TriangleMesh, IvecLess> IncrementalMesher::region_meshes(int p_region_blocks, const std::vector<glm::ivec3> &p_regions) const {
	std::map<glm::ivec3, TriangleMesh, IvecLess> out;
	for (const glm::ivec3 &region : p_regions) {
		out[region]; // empty unless a piece falls in it
	}
	for (const auto &[block, piece] : m_pieces) {
		const auto it = out.find(region_of(block, p_region_blocks));
		if (it != out.end()) {
			append_mesh(piece, &it->second);
		}
	}
	return out;
}

TriangleMesh IncrementalMesher::mesh() const {
	TriangleMesh mesh;
	for (const auto &[block, piece] : m_pieces) {
		append_mesh(piece, &mesh);
	}
	return mesh;
}

} // namespace roomprobe
