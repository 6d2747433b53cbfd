#pragma once

// Coarse room model (paper §4.1): the floorplan prism as a closed triangle mesh
// with a single light-map atlas in which every texel covers the same world area.

#include "floorplan.h"
#include <types/room_types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

enum class SurfaceKind {
	Wall,
	Floor,
	Ceiling,
};

// Settings for build_room_mesh().
struct RoomMeshOptions {
	double texel_size_m = 0.02; // World metres covered by one atlas texel edge, on every surface; must be > 0.
	int padding_texels = 2; // Empty texels between charts and along the atlas border (against bleeding); >= 0.
	int max_atlas_size = 8192; // Largest allowed atlas width and height, texels; building fails beyond it.
};

// One rectangular region of the atlas, holding one planar surface of the room.
//
// A texel position (px, py) in continuous atlas pixel units (texel (x, y) has
// its centre at (x + 0.5, y + 0.5)) maps to the world point
//   origin_m + u_axis_m * (px - x) + v_axis_m * (py - y),
// which lies on the surface as long as 0 <= px - x <= used_w_texels and
// 0 <= py - y <= used_h_texels (and, for floor/ceiling, inside the floorplan).
//
// Layout: each chart looks the right way round (not mirrored) when seen from
// inside the room with atlas +x to the right and +y downwards: walls have the
// ceiling at the top and run from points[i] (left) to points[i + 1] (right);
// the floor has +X right / +Z down, the ceiling +X right / -Z down.
struct Chart {
	SurfaceKind kind = SurfaceKind::Wall;
	int wall_index = -1; // Edge index i (points[i] -> points[i + 1]) of the normalized floorplan for walls, -1 otherwise.
	int x = 0; // Left column of the rect in the atlas, texels.
	int y = 0; // Top row of the rect in the atlas, texels.
	int w = 0; // Rect width, texels (used_w_texels rounded up).
	int h = 0; // Rect height, texels (used_h_texels rounded up).
	double used_w_texels = 0.0; // Exact surface extent along atlas x, texels (<= w).
	double used_h_texels = 0.0; // Exact surface extent along atlas y, texels (<= h).
	Vec3 origin_m; // World point at the rect's top-left corner (x, y), metres.
	Vec3 u_axis_m; // World step per texel along atlas +x, metres (length texel_size_m).
	Vec3 v_axis_m; // World step per texel along atlas +y, metres (length texel_size_m).
	Vec3 normal; // Unit surface normal, pointing into the room.
};

// The coarse room mesh as plain vertex/index arrays.
//
// Vertices are duplicated per chart (each chart has its own UVs), but the mesh
// is closed: welding equal positions, every edge is used by exactly two
// triangles in opposite directions.
//
// Winding: each triangle (a, b, c) is COUNTER-CLOCKWISE when seen from inside
// the room, i.e. from the side its normal points to: (b - a) x (c - a) is
// along the inward normal. Godot treats CLOCKWISE triangles as front faces, so
// the Godot layer must reverse each triangle (or disable culling) for the room
// to be visible from inside.
struct RoomMesh {
	Floorplan floorplan; // The normalized (counter-clockwise) floorplan the mesh was built from.
	double texel_size_m = 0.0; // World metres per texel, copied from the options.
	int atlas_width = 0; // Atlas width, texels (the packed extent, border padding included).
	int atlas_height = 0; // Atlas height, texels (the packed extent, border padding included).
	std::vector<Vec3f> positions; // Vertex positions, world metres.
	std::vector<Vec3f> normals; // Unit vertex normals, pointing into the room (flat per chart).
	std::vector<Vec2f> uvs; // Atlas UVs in [0, 1]; (0, 0) is the atlas's top-left texel corner.
	std::vector<uint32_t> indices; // Three vertex indices per triangle, see winding above.
	std::vector<int> triangle_charts; // Index into charts for each triangle (indices.size() / 3 entries).
	std::vector<int> vertex_charts; // Index into charts for each vertex (positions.size() entries).
	// Walls first (charts[i] is wall i), then the floor (charts[n]), then the
	// ceiling (charts[n + 1]), for a floorplan of n points.
	std::vector<Chart> charts;
};

// Outcome of build_room_mesh(); mesh is only meaningful when ok is true.
struct RoomMeshResult {
	bool ok = false;
	std::string error; // Human-readable reason when ok is false (invalid floorplan, options or atlas too large).
	RoomMesh mesh;
};

// Builds the coarse room: validates the floorplan (check_floorplan), normalizes
// it, emits one quad (two triangles) per wall, triangulates floor and ceiling
// with the polygon's constrained Delaunay triangulation of its corners only
// (polygon_triangulation.h), and packs all charts into an atlas.
// Never throws: every failure, CGAL's predicates' included, comes back as an error string.
RoomMeshResult build_room_mesh(const Floorplan &p_floorplan, const RoomMeshOptions &p_options = RoomMeshOptions());

// Index of the chart whose rect contains texel (p_x, p_y), or -1 (padding or outside the atlas).
int find_chart_at_texel(const RoomMesh &p_mesh, int p_x, int p_y);

// World point (metres) and inward unit normal at the centre of texel (p_x, p_y).
// Returns false, leaving the outputs untouched, when the texel centre is not on
// the room surface: outside every chart, in the unused rounding margin of a
// chart, or outside the floorplan polygon within the floor/ceiling chart.
// Either output pointer may be null.
bool texel_to_world(const RoomMesh &p_mesh, int p_x, int p_y, Vec3 *r_point, Vec3 *r_normal);

const char *surface_kind_name(SurfaceKind p_kind);

} // namespace roomprobe
