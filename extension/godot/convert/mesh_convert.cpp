#include "mesh_convert.h"

using namespace godot;

namespace roomprobe {

Array triangle_surface_arrays(const PackedVector3Array &p_vertices, const PackedVector3Array &p_normals, const std::vector<uint32_t> &p_indices) {
	PackedInt32Array indices;
	indices.resize(int64_t(p_indices.size()));
	int32_t *out = indices.ptrw(); // one pointer, not a call per element: meshes are large
	for (size_t t = 0; t + 2 < p_indices.size(); t += 3) {
		out[t] = int32_t(p_indices[t]);
		out[t + 1] = int32_t(p_indices[t + 2]);
		out[t + 2] = int32_t(p_indices[t + 1]);
	}
	Array arrays;
	arrays.resize(Mesh::ARRAY_MAX);
	arrays[Mesh::ARRAY_VERTEX] = p_vertices;
	arrays[Mesh::ARRAY_NORMAL] = p_normals;
	arrays[Mesh::ARRAY_INDEX] = indices;
	return arrays;
}

} // namespace roomprobe
