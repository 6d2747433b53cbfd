#pragma once

// The faces that line segments cut the plane into, as half-edges (room_estimation.cpp cuts the
// floor with its walls' lines). Where segments meet is computed exactly (CGAL's LGPL
// exact-constructions kernel), so three lines through one point meet in one vertex and no
// sliver face is lost or invented; coordinates come back as doubles.

#include <types/room_types.h>

#include <utility>
#include <vector>

namespace roomprobe {

struct SegmentArrangement {
	struct Halfedge {
		int source = -1; // index into vertices
		int target = -1;
		int twin = -1; // the same edge the other way
		int next = -1; // the next half-edge with the same face on its left
		int face = -1; // the face on its left: 0 is the unbounded one
	};
	struct Face {
		int halfedge = -1; // one half-edge of its boundary (-1 for the unbounded face)
		bool bounded = false;
	};
	std::vector<Vec2> vertices;
	// In pairs: 2 e and 2 e + 1 are the two sides of edge e. A bounded face's half-edges run
	// counter-clockwise; the unbounded face's run clockwise around each connected part.
	std::vector<Halfedge> halfedges;
	std::vector<Face> faces; // faces[0] is the unbounded face
};

// Every segment split where another touches, crosses or overlaps it. Segments of zero length
// are dropped; overlapping ones share their edges. A bounded face is taken to have no hole
// (nothing floats inside it unconnected): true for lines clipped to one box, which is how the
// room's estimation calls it; such a part would count as the unbounded face's. Never throws for
// finite input.
SegmentArrangement arrange_segments(const std::vector<std::pair<Vec2, Vec2>> &p_segments);

// The corners of bounded face p_face, counter-clockwise (its half-edges' sources in order).
std::vector<Vec2> face_polygon(const SegmentArrangement &p_arrangement, int p_face);

} // namespace roomprobe
