#pragma once
// Core triangle meshes into Godot's surface arrays.

#include <prt/prt_transfer.h>

#include <rp_godot/godot.h>

#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

// The arrays of one PRIMITIVE_TRIANGLES surface with vertices, normals and indices set (add UVs
// or colours to the result). Godot's front faces are clockwise, the core's counter-clockwise
// (seen from the side the normals point to): each triangle is reversed here.
godot::Array triangle_surface_arrays(const godot::PackedVector3Array &p_vertices, const godot::PackedVector3Array &p_normals,
		const std::vector<uint32_t> &p_indices);

// One surface of a Godot mesh as the PRT bake's mesh, in the surface's own vertex order (so that
// per-vertex data computed on it lines up with VERTEX_ID in a shader): Godot's clockwise
// triangles reversed to the core's counter-clockwise; an unindexed surface gets 0, 1, 2, ...;
// normals from the triangles when the surface has none. "" or why it cannot be converted.
std::string prt_mesh_from_surface(const godot::Ref<godot::Mesh> &p_mesh, int p_surface, PrtMesh *r_mesh);

} // namespace roomprobe
