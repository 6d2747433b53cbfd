#pragma once
// Core triangle meshes into Godot's surface arrays.

#include <rp_godot/godot.h>

#include <cstdint>
#include <vector>

namespace roomprobe {

// The arrays of one PRIMITIVE_TRIANGLES surface with vertices, normals and indices set (add UVs
// or colours to the result). Godot's front faces are clockwise, the core's counter-clockwise
// (seen from the side the normals point to): each triangle is reversed here.
godot::Array triangle_surface_arrays(const godot::PackedVector3Array &p_vertices, const godot::PackedVector3Array &p_normals,
		const std::vector<uint32_t> &p_indices);

} // namespace roomprobe
