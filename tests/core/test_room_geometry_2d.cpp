// The project's own 2-D geometry, which replaced CGAL's GPL packages (issue #37): the floor's
// constrained Delaunay triangulation, the visibility polygon and the arrangement of the room's
// wall lines, each against ground truth worked out by hand.

#include "coarse/occlusion.h"
#include "room/polygon_triangulation.h"
#include "room/reference_rooms.h"
#include "room/segment_arrangement.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

using namespace roomprobe;

namespace {

using Triangles = std::vector<std::array<size_t, 3>>;

Triangles triangulate(const std::vector<Vec2> &p_points) {
	std::vector<size_t> flat;
	std::string error;
	REQUIRE_MESSAGE(triangulate_polygon(p_points, &flat, &error), error);
	REQUIRE(flat.size() == 3 * (p_points.size() - 2));
	Triangles triangles;
	for (size_t i = 0; i < flat.size(); i += 3) {
		triangles.push_back({ flat[i], flat[i + 1], flat[i + 2] });
	}
	return triangles;
}

double cross(const Vec2 &p_a, const Vec2 &p_b, const Vec2 &p_c) {
	return (p_b.x - p_a.x) * (p_c.y - p_a.y) - (p_b.y - p_a.y) * (p_c.x - p_a.x);
}

// > 0 when p_d lies inside the circle through the counter-clockwise p_a, p_b, p_c.
double in_circle(const Vec2 &p_a, const Vec2 &p_b, const Vec2 &p_c, const Vec2 &p_d) {
	const double ax = p_a.x - p_d.x, ay = p_a.y - p_d.y, bx = p_b.x - p_d.x, by = p_b.y - p_d.y, cx = p_c.x - p_d.x, cy = p_c.y - p_d.y;
	return (ax * ax + ay * ay) * (bx * cy - by * cx) - (bx * bx + by * by) * (ax * cy - ay * cx) + (cx * cx + cy * cy) * (ax * by - ay * bx);
}

bool even_odd_inside(const std::vector<Vec2> &p_points, const Vec2 &p_point) {
	bool inside = false;
	for (size_t i = 0, j = p_points.size() - 1; i < p_points.size(); j = i++) {
		const Vec2 &a = p_points[i], &b = p_points[j];
		if ((a.y > p_point.y) != (b.y > p_point.y) && p_point.x < (b.x - a.x) * (p_point.y - a.y) / (b.y - a.y) + a.x) {
			inside = !inside;
		}
	}
	return inside;
}

double area(const std::vector<Vec2> &p_points) {
	double twice = 0.0;
	for (size_t i = 0; i < p_points.size(); ++i) {
		twice += cross({ 0.0, 0.0 }, p_points[i], p_points[(i + 1) % p_points.size()]);
	}
	return 0.5 * twice;
}

// A constrained Delaunay triangulation of the polygon with its corners only: counter-clockwise
// triangles inside it that add up to its area, each wall used once, each diagonal twice, and no
// diagonal's far corner inside the other triangle's circle.
void check_constrained_delaunay(const std::vector<Vec2> &p_points, const Triangles &p_triangles) {
	const size_t n = p_points.size();
	double total = 0.0;
	std::map<std::pair<size_t, size_t>, size_t> third; // directed edge -> opposite corner
	for (const auto &t : p_triangles) {
		const Vec2 &a = p_points[t[0]], &b = p_points[t[1]], &c = p_points[t[2]];
		CHECK(cross(a, b, c) > 0.0);
		total += 0.5 * cross(a, b, c);
		CHECK(even_odd_inside(p_points, { (a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0 }));
		for (int k = 0; k < 3; ++k) {
			CHECK(third.emplace(std::pair{ t[k], t[(k + 1) % 3] }, t[(k + 2) % 3]).second);
		}
	}
	CHECK(total == doctest::Approx(area(p_points)).epsilon(1e-12));
	for (const auto &[edge, c] : third) {
		const auto [a, b] = edge;
		const bool wall = (a + 1) % n == b || (b + 1) % n == a;
		const auto other = third.find({ b, a });
		CHECK(wall == (other == third.end()));
		if (wall) {
			CHECK((a + 1) % n == b); // walls run counter-clockwise inside the triangles
		} else if (other != third.end()) {
			CHECK(in_circle(p_points[a], p_points[b], p_points[c], p_points[other->second]) <= 1e-9);
		}
	}
}

// Whether two closed polygons have the same corners in the same cyclic order (within 1e-9 m).
bool same_cycle(const std::vector<glm::dvec2> &p_a, const std::vector<glm::dvec2> &p_b) {
	if (p_a.size() != p_b.size()) {
		return false;
	}
	for (size_t shift = 0; shift < p_b.size(); ++shift) {
		bool all = true;
		for (size_t i = 0; i < p_a.size() && all; ++i) {
			const glm::dvec2 d = p_a[i] - p_b[(i + shift) % p_b.size()];
			all = std::abs(d.x) < 1e-9 && std::abs(d.y) < 1e-9;
		}
		if (all) {
			return true;
		}
	}
	return false;
}

Floorplan plan_of(std::vector<Vec2> p_points) {
	Floorplan plan;
	plan.points = std::move(p_points);
	plan.ceiling_height_m = 2.5;
	return plan;
}

// A room with two thin baffles whose ends lie on the line z = 0: one from the far wall down to it,
// one from the near wall up to it, a little further on.
Floorplan baffled_room() {
	return plan_of({ { 0, -4 }, { 6, -4 }, { 6, 0 }, { 6.2, 0 }, { 6.2, -4 }, { 10, -4 }, { 10, 4 }, { 4.2, 4 }, { 4.2, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 } });
}

// The half-edge structure is consistent: twins pair up, next continues at the target, and a
// face's cycle keeps the face.
void check_structure(const SegmentArrangement &p_arrangement) {
	const auto &h = p_arrangement.halfedges;
	for (size_t i = 0; i < h.size(); ++i) {
		CHECK(h[h[i].twin].twin == int(i));
		CHECK(h[h[i].twin].source == h[i].target);
		CHECK(h[h[i].next].source == h[i].target);
		CHECK(h[h[i].next].face == h[i].face);
	}
}

} // namespace

TEST_CASE("room mesh triangulation: a rectangle's diagonal avoids its largest (x, z) corner, as CGAL's did") {
	// Both diagonals are Delaunay here; CGAL's constrained Delaunay triangulation took the one
	// from (max x, min z) to (min x, max z), wherever the corners start, and these triangles in
	// this order (a quadrilateral's keep it, see polygon_triangulation.h).
	CHECK(triangulate({ { 0, 0 }, { 5, 0 }, { 5, 4 }, { 0, 4 } }) == Triangles{ { 3, 1, 2 }, { 3, 0, 1 } });
	CHECK(triangulate({ { 5, 0 }, { 5, 4 }, { 0, 4 }, { 0, 0 } }) == Triangles{ { 0, 1, 2 }, { 3, 0, 2 } });
	CHECK(triangulate({ { -2, 1 }, { 3, 1 }, { 3, 4.5 }, { -2, 4.5 } }) == Triangles{ { 3, 1, 2 }, { 3, 0, 1 } });
	// A diamond's four corners are co-circular too: the diagonal avoids (1, 0).
	CHECK(triangulate({ { 0, -1 }, { 1, 0 }, { 0, 1 }, { -1, 0 } }) == Triangles{ { 0, 1, 2 }, { 3, 0, 2 } });
}

TEST_CASE("room mesh triangulation: a concave U-shaped room, by hand") {
	// A 5 x 4 room with a 3 x 3 notch from the top: the two arms and the bottom strip. The strip's
	// diagonals to the notch's corners are the only ones that keep every circle empty.
	// Each arm (0, 5, 6, 7) and (1, 2, 3, 4) is a trapezoid whose circle through three corners
	// leaves the fourth out only for the diagonals 5-7 and 2-4 (its right angle's circle has the
	// other diagonal as diameter, e.g. centre (0.5, 2.5), r^2 2.5, and (0, 0) at 6.5 outside).
	// The strip's trapezoid (0, 1, 4, 5) is co-circular: its diagonal avoids (5, 0), so 0-4.
	const std::vector<Vec2> u = { { 0, 0 }, { 5, 0 }, { 5, 4 }, { 4, 4 }, { 4, 1 }, { 1, 1 }, { 1, 4 }, { 0, 4 } };
	const Triangles triangles = triangulate(u);
	check_constrained_delaunay(u, triangles);
	CHECK(triangles == Triangles{ { 0, 1, 4 }, { 0, 4, 5 }, { 0, 5, 7 }, { 1, 2, 4 }, { 2, 3, 4 }, { 5, 6, 7 } });
}

TEST_CASE("room mesh triangulation: corners in the middle of a wall, the reference rooms and random star rooms are constrained Delaunay") {
	const std::vector<Vec2> straight = { { 0, 0 }, { 2, 0 }, { 4, 0 }, { 4, 3 }, { 0, 3 } };
	check_constrained_delaunay(straight, triangulate(straight));
	for (const Floorplan &plan : { living_room(), l_shaped_room(), figure4_two_rooms() }) {
		check_constrained_delaunay(plan.points, triangulate(plan.points));
	}
	std::mt19937 random(11);
	std::uniform_real_distribution<double> radius(1.0, 4.0);
	for (int k = 0; k < 40; ++k) {
		std::vector<Vec2> star;
		const int n = 5 + k % 20;
		for (int i = 0; i < n; ++i) {
			const double angle = 2.0 * M_PI * i / n, r = radius(random);
			star.push_back({ r * std::cos(angle), r * std::sin(angle) });
		}
		CAPTURE(k);
		check_constrained_delaunay(star, triangulate(star));
	}
}

TEST_CASE("room mesh triangulation: a repeated corner or a clockwise polygon is an error, not a throw") {
	std::vector<size_t> triangles;
	std::string error;
	CHECK_FALSE(triangulate_polygon({ { 0, 0 }, { 2, 0 }, { 2, 2 }, { 0, 0 }, { 0, 2 } }, &triangles, &error));
	CHECK(error.find("same point") != std::string::npos);
	CHECK_FALSE(triangulate_polygon({ { 0, 0 }, { 0, 2 }, { 2, 2 }, { 2, 0 }, { 1, 1 } }, &triangles, &error));
	CHECK_FALSE(triangulate_polygon({ { 0, 0 }, { 1, 0 } }, &triangles, &error));
	CHECK_FALSE(triangulate_polygon({ { 0, 0 }, { 1, 0 }, { NAN, 1 } }, &triangles, &error));
}

TEST_CASE("visibility polygon: from the L-shaped room's short arm the long arm is cut at the reflex corner's shadow") {
	// L: x 0..6, z 0..3 plus x 0..3, z 3..5. From (5, 1) the ray past the reflex corner (3, 3)
	// runs along z = 6 - x to the far wall z = 5 at x = 1: the corner (3, 5) and x > 1 up there are hidden.
	const VisibilityPolygon v = visibility_polygon(l_shaped_room(), glm::dvec2(5.0, 1.0));
	REQUIRE_MESSAGE(v.ok, v.error);
	CHECK(same_cycle(v.points, { { 6, 0 }, { 6, 3 }, { 3, 3 }, { 1, 5 }, { 0, 5 }, { 0, 0 } }));
	CHECK_FALSE(point_in_polygon(v.points, glm::dvec2(2.0, 4.8)));
	CHECK(point_in_polygon(v.points, glm::dvec2(0.5, 4.8)));
}

TEST_CASE("visibility polygon: a viewpoint in line with a wall or grazing a corner sees the whole L") {
	const std::vector<glm::dvec2> l = { { 0, 0 }, { 6, 0 }, { 6, 3 }, { 3, 3 }, { 3, 5 }, { 0, 5 } };
	for (const glm::dvec2 &q : { glm::dvec2(1.0, 3.0), glm::dvec2(3.0, 1.0), glm::dvec2(2.0, 2.0) }) {
		CAPTURE(q.x);
		CAPTURE(q.y);
		const VisibilityPolygon v = visibility_polygon(l_shaped_room(), q);
		REQUIRE_MESSAGE(v.ok, v.error);
		CHECK(same_cycle(v.points, l));
	}
}

TEST_CASE("visibility polygon: a ray between two baffles' ends leaves no needle") {
	// From (2, 0) the line z = 0 passes the ends of both baffles: only the line itself would see
	// the far wall beyond x = 6.2. The region: the near part up to the first baffle (x = 4), and
	// under it up to the second (x = 6); 32 + 8 m^2.
	const VisibilityPolygon v = visibility_polygon(baffled_room(), glm::dvec2(2.0, 0.0));
	REQUIRE_MESSAGE(v.ok, v.error);
	CHECK(same_cycle(v.points, { { 6, 0 }, { 4, 0 }, { 4, 4 }, { 0, 4 }, { 0, -4 }, { 6, -4 } }));
	double twice = 0.0;
	for (size_t i = 0; i < v.points.size(); ++i) {
		const glm::dvec2 &a = v.points[i], &b = v.points[(i + 1) % v.points.size()];
		twice += a.x * b.y - b.x * a.y;
	}
	CHECK(0.5 * twice == doctest::Approx(40.0));
}

TEST_CASE("visibility polygon: on a wall, at a corner or outside is refused; just inside a wall works; repeats are dropped") {
	const Floorplan l = l_shaped_room();
	CHECK_FALSE(visibility_polygon(l, glm::dvec2(0.0, 2.0)).ok); // on a wall
	CHECK_FALSE(visibility_polygon(l, glm::dvec2(3.0, 3.0)).ok); // at the reflex corner
	CHECK_FALSE(visibility_polygon(l, glm::dvec2(4.0, 4.0)).ok); // in the notch, outside
	const VisibilityPolygon near = visibility_polygon(l, glm::dvec2(1e-9, 4.0));
	REQUIRE_MESSAGE(near.ok, near.error);
	CHECK(point_in_polygon(near.points, glm::dvec2(5.5, 0.5)));
	CHECK_FALSE(point_in_polygon(near.points, glm::dvec2(5.5, 2.9)));
	const Floorplan repeated = plan_of({ { 0, 0 }, { 6, 0 }, { 6, 3 }, { 6, 3 }, { 3, 3 }, { 3, 5 }, { 0, 5 }, { 0, 0 } });
	const VisibilityPolygon again = visibility_polygon(repeated, glm::dvec2(5.0, 1.0));
	REQUIRE_MESSAGE(again.ok, again.error);
	CHECK(same_cycle(again.points, { { 6, 0 }, { 6, 3 }, { 3, 3 }, { 1, 5 }, { 0, 5 }, { 0, 0 } }));
	CHECK_FALSE(visibility_polygon(plan_of({ { 0, 0 }, { 2, 2 }, { 2, 0 }, { 0, 2 } }), glm::dvec2(1.0, 0.5)).ok); // a bow-tie
}

TEST_CASE("room arrangement: two crossing segments make one vertex more and no bounded face") {
	const SegmentArrangement a = arrange_segments({ { { 0, 0 }, { 2, 2 } }, { { 0, 2 }, { 2, 0 } } });
	CHECK(a.vertices.size() == 5);
	CHECK(a.halfedges.size() == 8);
	CHECK(a.faces.size() == 1);
	check_structure(a);
}

TEST_CASE("room arrangement: a noughts-and-crosses grid clipped to its box closes only the middle square") {
	const SegmentArrangement a = arrange_segments(
			{ { { 1, 0 }, { 1, 3 } }, { { 2, 0 }, { 2, 3 } }, { { 0, 1 }, { 3, 1 } }, { { 0, 2 }, { 3, 2 } }, { { 0.5, 0.5 }, { 0.5, 0.5 } } });
	CHECK(a.vertices.size() == 12);
	CHECK(a.halfedges.size() == 24);
	REQUIRE(a.faces.size() == 2);
	CHECK(a.faces[1].bounded);
	const std::vector<Vec2> square = face_polygon(a, 1);
	CHECK(square.size() == 4);
	CHECK(area(square) == doctest::Approx(1.0));
	for (const Vec2 &p : square) {
		CHECK(((p.x == 1 || p.x == 2) && (p.y == 1 || p.y == 2)));
	}
	check_structure(a);
}

TEST_CASE("room arrangement: three lines through (1/3, 1/3) meet in one vertex, not a sliver") {
	// The meeting point has no double: pairwise rounded crossings would leave a tiny triangle.
	const SegmentArrangement a = arrange_segments({ { { -2, -2 }, { 2, -2 } }, { { 2, -2 }, { 2, 2 } }, { { 2, 2 }, { -2, 2 } }, { { -2, 2 }, { -2, -2 } },
			{ { -2, -2 }, { 2, 2 } }, { { -0.5, 2 }, { 1.5, -2 } }, { { -2, 1.5 }, { 2, -0.5 } } });
	CHECK(a.vertices.size() == 9);
	REQUIRE(a.faces.size() == 7);
	double total = 0.0;
	for (size_t f = 1; f < a.faces.size(); ++f) {
		CHECK(a.faces[f].bounded);
		const std::vector<Vec2> face = face_polygon(a, int(f));
		CHECK(face.size() <= 4);
		CHECK(area(face) > 0.1);
		total += area(face);
	}
	CHECK(total == doctest::Approx(16.0));
	const auto centre = std::find_if(a.vertices.begin(), a.vertices.end(), [](const Vec2 &p_v) { return std::abs(p_v.x - 1.0 / 3.0) < 1e-12; });
	REQUIRE(centre != a.vertices.end());
	CHECK(std::count_if(a.halfedges.begin(), a.halfedges.end(), [&](const SegmentArrangement::Halfedge &p_h) {
		return p_h.source == int(centre - a.vertices.begin());
	}) == 6);
	check_structure(a);
}

TEST_CASE("room arrangement: overlapping collinear segments share their edges") {
	const SegmentArrangement a = arrange_segments({ { { 0, 0 }, { 2, 0 } }, { { 3, 0 }, { 1, 0 } }, { { 1, 0 }, { 1, 1 } } });
	CHECK(a.vertices.size() == 5);
	CHECK(a.halfedges.size() == 8); // (0-1), (1-2), (2-3) on the line, (1,0)-(1,1) up
	CHECK(a.faces.size() == 1);
	check_structure(a);
}
