// The region of the floorplan a viewpoint sees (occlusion.h's visibility_polygon): an angular
// sweep. The directions from the viewpoint to the corners cut the full turn into wedges; no corner
// lies inside a wedge, so one wall is nearest all across it, and the region is the union of the
// triangles (viewpoint, that wall's part in the wedge). Every decision (direction order, which
// wall spans a wedge, which is nearer) is one of CGAL's exact predicates (its LGPL kernel); only
// the output points are computed, in doubles. Rays grazing a corner cost nothing special: the
// region is a union of open wedges' triangles, so it has no needles. O(n^2) for n corners.

#include "occlusion.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2_algorithms.h>

#include <algorithm>
#include <exception>
#include <utility>

namespace roomprobe {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_2;

// A wall as the viewpoint sees it: its ends in counter-clockwise order around the viewpoint.
struct Wall {
	Point s, t;
};

class Sweep {
public:
	explicit Sweep(const Point &p_viewpoint) :
			q(p_viewpoint) {}

	// Whether the direction to p_a comes strictly before the one to p_b, counter-clockwise from +x.
	bool before(const Point &p_a, const Point &p_b) const {
		const int ha = half(p_a), hb = half(p_b);
		return ha != hb ? ha < hb : CGAL::orientation(q, p_a, p_b) == CGAL::LEFT_TURN;
	}

	bool same_direction(const Point &p_a, const Point &p_b) const {
		return half(p_a) == half(p_b) && CGAL::orientation(q, p_a, p_b) == CGAL::COLLINEAR;
	}

	// False for a wall seen edge-on: it hides nothing.
	bool make_wall(const Point &p_a, const Point &p_b, Wall *r_wall) const {
		const CGAL::Orientation o = CGAL::orientation(q, p_a, p_b);
		if (o == CGAL::COLLINEAR) {
			return false;
		}
		*r_wall = o == CGAL::LEFT_TURN ? Wall{ p_a, p_b } : Wall{ p_b, p_a };
		return true;
	}

	// Whether the direction to p_point lies in the wall's angle, ends included (the angle is
	// below a half-turn, so two orientations decide it).
	bool covers(const Wall &p_wall, const Point &p_point) const {
		return CGAL::orientation(q, p_wall.s, p_point) != CGAL::RIGHT_TURN && CGAL::orientation(q, p_point, p_wall.t) != CGAL::RIGHT_TURN;
	}

	// Whether p_a is nearer than p_b across the directions both cover. Walls of a simple polygon
	// do not cross, so one lies wholly on one side of the other there: the ends of the shared
	// angle (the later start, the earlier end) tell which, unless the walls meet at that end.
	bool nearer(const Wall &p_a, const Wall &p_b) const {
		const bool b_starts_later = CGAL::orientation(q, p_a.s, p_b.s) == CGAL::LEFT_TURN;
		const bool b_ends_earlier = CGAL::orientation(q, p_a.t, p_b.t) == CGAL::RIGHT_TURN;
		const std::pair<Point, bool> ends[2] = { { b_starts_later ? p_b.s : p_a.s, !b_starts_later }, { b_ends_earlier ? p_b.t : p_a.t, !b_ends_earlier } };
		for (const auto &[point, on_a] : ends) { // on_a: the end is p_a's
			const Wall &other = on_a ? p_b : p_a;
			const CGAL::Orientation o = CGAL::orientation(other.s, other.t, point);
			if (o != CGAL::COLLINEAR) {
				const bool point_in_front = o == CGAL::LEFT_TURN; // on the viewpoint's side of the other wall
				return on_a == point_in_front;
			}
		}
		return false; // the same wall twice
	}

	// Where the ray towards p_ray meets the wall: a wall end or p_ray itself when exactly on it.
	glm::dvec2 hit(const Wall &p_wall, const Point &p_ray) const {
		for (const Point &end : { p_wall.s, p_wall.t }) {
			if (same_direction(end, p_ray)) {
				return glm::dvec2(end.x(), end.y());
			}
		}
		if (CGAL::orientation(p_wall.s, p_wall.t, p_ray) == CGAL::COLLINEAR) {
			return glm::dvec2(p_ray.x(), p_ray.y());
		}
		const glm::dvec2 origin(q.x(), q.y()), s(p_wall.s.x(), p_wall.s.y()), t(p_wall.t.x(), p_wall.t.y());
		const glm::dvec2 d = glm::dvec2(p_ray.x(), p_ray.y()) - origin, e = t - s, f = s - origin;
		const double along = (f.x * e.y - f.y * e.x) / (d.x * e.y - d.y * e.x);
		return origin + along * d;
	}

private:
	Point q;

	// 0 for directions at angles [0, pi) from +x, 1 for [pi, 2 pi): coordinates compare exactly.
	int half(const Point &p_point) const {
		return p_point.y() > q.y() || (p_point.y() == q.y() && p_point.x() > q.x()) ? 0 : 1;
	}
};

// One corner per distinct direction, counter-clockwise from +x.
std::vector<Point> corner_directions(const Sweep &p_sweep, std::vector<Point> p_corners) {
	std::sort(p_corners.begin(), p_corners.end(), [&](const Point &p_a, const Point &p_b) { return p_sweep.before(p_a, p_b); });
	std::vector<Point> rays;
	for (const Point &p : p_corners) {
		if (rays.empty() || !p_sweep.same_direction(rays.back(), p)) {
			rays.push_back(p);
		}
	}
	return rays;
}

// The wall nearest the viewpoint across the wedge between two consecutive directions, or -1.
int nearest_wall(const Sweep &p_sweep, const std::vector<Wall> &p_walls, const Point &p_from, const Point &p_to) {
	int best = -1;
	for (size_t i = 0; i < p_walls.size(); ++i) {
		if (p_sweep.covers(p_walls[i], p_from) && p_sweep.covers(p_walls[i], p_to) && (best < 0 || p_sweep.nearer(p_walls[i], p_walls[best]))) {
			best = int(i);
		}
	}
	return best;
}

// The corners of the floorplan with consecutive repeats dropped (a zero-length wall hides nothing).
std::vector<Point> distinct_corners(const Floorplan &p_floorplan) {
	std::vector<Point> corners;
	for (const Vec2 &p : p_floorplan.points) {
		const Point point(p.x, p.y);
		if (corners.empty() || corners.back() != point) {
			corners.push_back(point);
		}
	}
	while (corners.size() > 1 && corners.front() == corners.back()) {
		corners.pop_back();
	}
	return corners;
}

VisibilityPolygon trace_visibility(const std::vector<Point> &p_corners, const Point &p_viewpoint) {
	VisibilityPolygon result;
	const Sweep sweep(p_viewpoint);
	std::vector<Wall> walls;
	for (size_t i = 0; i < p_corners.size(); ++i) {
		Wall wall;
		if (sweep.make_wall(p_corners[i], p_corners[(i + 1) % p_corners.size()], &wall)) {
			walls.push_back(wall);
		}
	}
	const std::vector<Point> rays = corner_directions(sweep, p_corners);
	const size_t m = rays.size();
	std::vector<int> nearest(m);
	for (size_t k = 0; k < m; ++k) {
		nearest[k] = nearest_wall(sweep, walls, rays[k], rays[(k + 1) % m]);
		if (nearest[k] < 0) { // only for a viewpoint outside: checked before
			result.error = "no wall bounds the view between two corners";
			return result;
		}
	}
	// At each corner direction the region's boundary steps from the wall nearest before it to the
	// wall nearest after it (one point where they meet there).
	for (size_t k = 0; k < m; ++k) {
		const int before = nearest[(k + m - 1) % m], after = nearest[k];
		if (before != after) {
			for (const glm::dvec2 &p : { sweep.hit(walls[before], rays[k]), sweep.hit(walls[after], rays[k]) }) {
				if (result.points.empty() || result.points.back() != p) {
					result.points.push_back(p);
				}
			}
		}
	}
	while (result.points.size() > 1 && result.points.front() == result.points.back()) {
		result.points.pop_back();
	}
	result.ok = result.points.size() >= 3;
	if (!result.ok) {
		result.error = "the visible region is degenerate";
	}
	return result;
}

} // namespace

VisibilityPolygon visibility_polygon(const Floorplan &p_floorplan, const glm::dvec2 &p_viewpoint_xz) {
	VisibilityPolygon result;
	try {
		const std::vector<Point> corners = distinct_corners(p_floorplan);
		if (corners.size() < 3) {
			result.error = "the floorplan has fewer than 3 points";
			return result;
		}
		if (!CGAL::is_simple_2(corners.begin(), corners.end(), Kernel())) {
			result.error = "the floorplan is not a simple polygon";
			return result;
		}
		const Point q(p_viewpoint_xz.x, p_viewpoint_xz.y);
		if (CGAL::bounded_side_2(corners.begin(), corners.end(), q, Kernel()) != CGAL::ON_BOUNDED_SIDE) {
			result.error = "the viewpoint is not strictly inside the floorplan";
			return result;
		}
		return trace_visibility(corners, q);
	} catch (const std::exception &e) {
		// CGAL's predicates throw on a failed precondition (NaN input); none may leave the core.
		result = VisibilityPolygon();
		result.error = std::string("visibility polygon failed: ") + e.what();
	}
	return result;
}

} // namespace roomprobe
