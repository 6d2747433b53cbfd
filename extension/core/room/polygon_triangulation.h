#pragma once

// Triangulating a floorplan polygon with its corners only (no Steiner points, so the floor and
// ceiling edges match the walls): ear clipping, then Lawson flips of the inner diagonals until
// every one is locally Delaunay, which makes it the polygon's constrained Delaunay triangulation.
// Decisions use CGAL's exact predicates (its LGPL kernel); no point is ever constructed.

#include <types/room_types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace roomprobe {

// p_points: a simple polygon, counter-clockwise (floorplan.h's convention); corners in the
// middle of a straight wall are allowed, repeated points are not.
//
// r_triangles: 3 (n - 2) corner indices, three a triangle, each triangle counter-clockwise and
// starting at its smallest index, the triangles in lexicographic order of their indices; but a
// quadrilateral's come as CGAL's triangulation gave them ((3, 1, 2), (3, 0, 1) with the
// diagonal 1-3, else (0, 1, 2), (3, 0, 2)), so that a rectangular room's mesh, and what is
// rendered from it, is the same as before to the bit.
//
// Where four or more corners lie on one circle (a rectangle's four), more than one answer is
// Delaunay; the choice is a symbolic perturbation that raises each corner's lifted height
// x^2 + y^2 by a tiny amount that shrinks fast with the corner's lexicographic (x, then y) rank,
// the largest corner raised most: a co-circular quad's diagonal avoids its lexicographically
// largest corner (a rectangle's runs between its (min x, max y) and (max x, min y) corners).
// CGAL's constrained Delaunay triangulation, which this replaced, chose the same there.
//
// False, with r_error, when the polygon has fewer than 3 points, repeats a point, or is not
// simple or not counter-clockwise (no ear to clip). Never throws.
bool triangulate_polygon(const std::vector<Vec2> &p_points, std::vector<std::size_t> *r_triangles, std::string *r_error);

} // namespace roomprobe
