#pragma once

// The coarse room description of the paper (§4.1): a floorplan polygon and a
// ceiling height. The room is the polygon extruded from the floor (world y = 0)
// up to the ceiling (world y = ceiling_height_m).

#include <types/room_types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace roomprobe {

// The Floorplan itself, its coordinates and orientation convention: types/room_types.h.

// Result of check_floorplan(). When ok is true, problem is None and message is empty.
struct FloorplanCheck {
	enum class Problem {
		None,
		TooFewPoints, // Fewer than 3 points.
		SelfIntersecting, // Edges cross, touch, fold back, or have zero length (repeated point).
		ZeroArea, // All points collinear (or the polygon otherwise encloses no area).
		CeilingNotPositive, // ceiling_height_m <= 0.
		NonFinite, // A coordinate or the ceiling height is NaN or infinite.
		TooManyPoints, // More than FLOORPLAN_MAX_POINTS points.
	};

	bool ok = true;
	Problem problem = Problem::None;
	std::string message; // Human-readable: names the offending points/edges/values.
};

// Checks that the floorplan describes a buildable room: finite numbers, at
// least 3 points, a positive ceiling, no repeated consecutive points, a simple
// (non-self-intersecting) polygon with non-zero area. Either orientation is
// accepted. Reports only the first problem found, checking in this order:
// TooManyPoints (before reading a point), NonFinite, TooFewPoints, CeilingNotPositive, repeated consecutive points
// (SelfIntersecting), all points collinear (ZeroArea), crossing/touching edges
// (SelfIntersecting). Never throws (the core is exception-free at its API).
FloorplanCheck check_floorplan(const Floorplan &p_floorplan);

// The problem in a sentence for the user, e.g. "The floorplan is self-intersecting"; the
// check's message adds which points or edges.
const char *floorplan_problem_summary(FloorplanCheck::Problem p_problem);

// Signed polygon area in square metres in the (x, z) plane: positive when the
// points are counter-clockwise (the normalized convention), negative when clockwise.
double floorplan_signed_area_m2(const Floorplan &p_floorplan);
// The same for a bare polygon (the room's estimation works on polygons before they are floorplans).
double polygon_signed_area_m2(const std::vector<Vec2> &p_points);
// Whether p_point lies inside the polygon (crossing rule; either orientation).
bool polygon_contains(const std::vector<Vec2> &p_points, const Vec2 &p_point);

// Length of the closed polygon boundary in metres (sum of all wall widths).
double floorplan_perimeter_m(const Floorplan &p_floorplan);

// True if the points are counter-clockwise in the (x, z) plane (see above).
// Meaningful for floorplans that pass check_floorplan().
bool is_counter_clockwise(const Floorplan &p_floorplan);

// How far p_point (room frame: x, y up, z) lies outside the room's prism, in metres: 0 inside or
// on it. A probe far outside sees the room from behind its walls, a map of nothing, so RoomProbe
// warns (issue #17). Meant for floorplans that pass check_floorplan().
double distance_outside_room_m(const Floorplan &p_floorplan, const Vec3 &p_point);

// Returns the floorplan in the normalized (counter-clockwise) orientation.
// A clockwise polygon is reversed while keeping points[0] first, so that the
// result is points[0], points[n-1], ..., points[1]; an already counter-clockwise
// one is returned unchanged. Wall indices refer to the normalized order.
// Meant for floorplans that pass check_floorplan().
Floorplan normalized(const Floorplan &p_floorplan);

} // namespace roomprobe
