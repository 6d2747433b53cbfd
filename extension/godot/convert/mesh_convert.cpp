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

std::string prt_mesh_from_surface(const Ref<Mesh> &p_mesh, int p_surface, PrtMesh *r_mesh) {
	*r_mesh = PrtMesh();
	if (p_mesh.is_null()) {
		return "no mesh";
	}
	if (p_surface < 0 || p_surface >= p_mesh->get_surface_count()) {
		return "the mesh has no surface " + std::to_string(p_surface) + " (it has " + std::to_string(p_mesh->get_surface_count()) + ")";
	}
	const Array arrays = p_mesh->surface_get_arrays(p_surface);
	if (arrays.size() < Mesh::ARRAY_MAX) {
		return "surface " + std::to_string(p_surface) + " has no arrays";
	}
	const PackedVector3Array vertices = arrays[Mesh::ARRAY_VERTEX];
	const PackedVector3Array normals = arrays[Mesh::ARRAY_NORMAL];
	const PackedInt32Array indices = arrays[Mesh::ARRAY_INDEX];
	if (vertices.is_empty()) {
		return "surface " + std::to_string(p_surface) + " has no vertices";
	}
	const Vector3 *v = vertices.ptr();
	for (int64_t i = 0; i < vertices.size(); i++) {
		r_mesh->positions.emplace_back(v[i].x, v[i].y, v[i].z);
	}
	const int64_t index_count = indices.is_empty() ? vertices.size() : indices.size();
	if (index_count % 3 != 0) {
		return "surface " + std::to_string(p_surface) + " is not made of triangles (" + std::to_string(index_count) + " indices)";
	}
	const int32_t *idx = indices.is_empty() ? nullptr : indices.ptr();
	for (int64_t t = 0; t < index_count; t += 3) {
		for (int64_t k : { 0, 2, 1 }) {
			const int64_t i = idx ? idx[t + k] : t + k;
			if (i < 0 || i >= vertices.size()) {
				return "surface " + std::to_string(p_surface) + ": index " + std::to_string(t + k) + " is out of range";
			}
			r_mesh->indices.push_back(uint32_t(i));
		}
	}
	if (normals.size() == vertices.size()) {
		const Vector3 *n = normals.ptr();
		for (int64_t i = 0; i < normals.size(); i++) {
			const real_t length = n[i].length();
			const Vector3 unit = length > 0 ? n[i] * (1 / length) : Vector3(0, 1, 0);
			r_mesh->normals.emplace_back(unit.x, unit.y, unit.z);
		}
	} else {
		compute_vertex_normals(r_mesh);
	}
	return check_prt_mesh(*r_mesh);
}

} // namespace roomprobe
