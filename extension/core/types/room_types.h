#pragma once

// The ground floor's plain room types: vectors and the floorplan (paper §4.1), used by the room,
// the recordings and the Godot layer alike (which converts them to Vector2/Vector3). The
// floorplan's checks and geometry are in room/floorplan.h.

#include <cstddef>
#include <vector>

namespace roomprobe {

// A 2-D point or vector in double precision. For floorplans, x is world X and
// y is world Z (metres), see floorplan.h.
struct Vec2 {
	double x = 0.0;
	double y = 0.0;
};

// A 3-D point or vector in double precision (world space: Y-up, metres).
struct Vec3 {
	double x = 0.0;
	double y = 0.0;
	double z = 0.0;
};

// Single-precision 2-D vector, as GPU vertex data (atlas UVs).
struct Vec2f {
	float x = 0.0f;
	float y = 0.0f;
};

// Single-precision 3-D vector, as GPU vertex data (positions in metres, unit normals).
struct Vec3f {
	float x = 0.0f;
	float y = 0.0f;
	float z = 0.0f;
};

// Coordinates: floorplan point p maps to world (p.x, 0, p.y) on the floor and
// (p.x, ceiling_height_m, p.y) at the ceiling, i.e. Vec2::y holds world Z.
//
// Orientation convention: a *normalized* floorplan lists its points
// counter-clockwise in the 2-D (x, z) plane as CGAL sees the coordinates
// (x to the right, z upwards on paper), so the room interior lies to the LEFT
// of every edge points[i] -> points[i + 1]. Beware: seen from above in Godot's
// right-handed Y-up world (camera at +Y looking down, X to the right, so +Z
// points down the screen) the same polygon appears CLOCKWISE.
//
// Edges and walls are numbered like the points: edge i runs from points[i] to
// points[(i + 1) % n]. All indices in messages are 0-based.
struct Floorplan {
	std::vector<Vec2> points; // Polygon corners, metres; implicitly closed (last connects to first).
	double ceiling_height_m = 0.0; // Floor-to-ceiling height, metres; must be > 0.
};

// The most corners a floorplan may have. A room's walls number in the tens; the checks and the
// room mesh grow with the square of the count, so a 100000-point polygon (a point cloud pasted
// by mistake) once held the editor's main thread for minutes. Refused before anything else runs.
inline constexpr std::size_t FLOORPLAN_MAX_POINTS = 1024;

} // namespace roomprobe
