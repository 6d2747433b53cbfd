#pragma once

// Internal to the room module: the CGAL kernel and conversions it uses.
// Kept out of the public headers so that users of floorplan.h / room_mesh.h
// do not pull in CGAL.

#include "floorplan.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>

#include <vector>

namespace roomprobe::room_cgal {

// Exact predicates keep orientation/intersection tests robust for nearly
// collinear walls; constructions (centroids etc.) are not needed.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_2;
using Segment = Kernel::Segment_2;
using Polygon = CGAL::Polygon_2<Kernel>;

inline Point to_cgal(const Vec2 &p_point) {
	return Point(p_point.x, p_point.y);
}

inline Polygon to_polygon(const std::vector<Vec2> &p_points) {
	Polygon polygon;
	for (const Vec2 &point : p_points) {
		polygon.push_back(to_cgal(point));
	}
	return polygon;
}

} // namespace roomprobe::room_cgal
