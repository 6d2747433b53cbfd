#include "polygon_triangulation.h"

#include "room_cgal.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <exception>
#include <numeric>
#include <unordered_map>
#include <utility>

namespace roomprobe {

namespace {

using room_cgal::Point;
using Triangle = std::array<std::size_t, 3>;

bool in_closed_triangle(const Point &p_a, const Point &p_b, const Point &p_c, const Point &p_point) {
	return CGAL::orientation(p_a, p_b, p_point) != CGAL::RIGHT_TURN && CGAL::orientation(p_b, p_c, p_point) != CGAL::RIGHT_TURN &&
			CGAL::orientation(p_c, p_a, p_point) != CGAL::RIGHT_TURN;
}

// ring[k] is an ear: strictly convex (a straight corner would give a flat triangle), and no other
// remaining corner lies in or on the triangle it cuts off, so its two neighbours see each other.
bool is_ear(const std::vector<Point> &p_points, const std::vector<std::size_t> &p_ring, std::size_t p_k) {
	const std::size_t m = p_ring.size();
	const std::size_t a = p_ring[(p_k + m - 1) % m], b = p_ring[p_k], c = p_ring[(p_k + 1) % m];
	if (CGAL::orientation(p_points[a], p_points[b], p_points[c]) != CGAL::LEFT_TURN) {
		return false;
	}
	for (const std::size_t w : p_ring) {
		if (w != a && w != b && w != c && in_closed_triangle(p_points[a], p_points[b], p_points[c], p_points[w])) {
			return false;
		}
	}
	return true;
}

// Any triangulation of the polygon; false when no ear is left (not simple, or clockwise).
bool clip_ears(const std::vector<Point> &p_points, std::vector<Triangle> *r_triangles) {
	std::vector<std::size_t> ring(p_points.size());
	std::iota(ring.begin(), ring.end(), std::size_t(0));
	std::size_t k = 0, misses = 0;
	while (ring.size() > 3) {
		if (misses > ring.size()) {
			return false;
		}
		k %= ring.size();
		if (!is_ear(p_points, ring, k)) {
			k++;
			misses++;
			continue;
		}
		const std::size_t m = ring.size();
		r_triangles->push_back({ ring[(k + m - 1) % m], ring[k], ring[(k + 1) % m] });
		ring.erase(ring.begin() + long(k));
		k = (k + ring.size() - 1) % ring.size(); // the corner before may have become an ear
		misses = 0;
	}
	if (CGAL::orientation(p_points[ring[0]], p_points[ring[1]], p_points[ring[2]]) != CGAL::LEFT_TURN) {
		return false;
	}
	r_triangles->push_back({ ring[0], ring[1], ring[2] });
	return true;
}

// Whether the diagonal a-b shared by the counter-clockwise triangles (a, b, c) and (b, a, d)
// must become c-d: d lies inside the circle through a, b and c. On the circle, the perturbation
// of the header decides: the diagonal avoids the largest corner of the four, lifted the most.
bool must_flip(const std::vector<Point> &p_points, std::size_t p_a, std::size_t p_b, std::size_t p_c, std::size_t p_d) {
	const CGAL::Oriented_side side = CGAL::side_of_oriented_circle(p_points[p_a], p_points[p_b], p_points[p_c], p_points[p_d]);
	if (side != CGAL::ON_ORIENTED_BOUNDARY) {
		return side == CGAL::ON_POSITIVE_SIDE;
	}
	std::size_t largest = p_a;
	for (const std::size_t i : { p_b, p_c, p_d }) {
		if (CGAL::compare_xy(p_points[i], p_points[largest]) == CGAL::LARGER) {
			largest = i;
		}
	}
	return largest == p_a || largest == p_b;
}

// The triangles with each directed edge's owner (the triangle holding it counter-clockwise).
class FlipMesh {
public:
	FlipMesh(std::size_t p_corners, std::vector<Triangle> p_triangles) :
			corners(p_corners), triangles(std::move(p_triangles)) {
		for (std::size_t t = 0; t < triangles.size(); ++t) {
			own(t);
		}
	}

	// Lawson's flips from every diagonal; false if they do not settle (never for exact predicates).
	bool make_delaunay(const std::vector<Point> &p_points) {
		std::vector<std::pair<std::size_t, std::size_t>> stack;
		for (const Triangle &t : triangles) {
			for (int i = 0; i < 3; ++i) {
				push_diagonal(t[i], t[(i + 1) % 3], &stack);
			}
		}
		std::size_t budget = 4 * corners * corners + 64;
		while (!stack.empty()) {
			const auto [a, b] = stack.back();
			stack.pop_back();
			const auto t = owner.find(key(a, b)), u = owner.find(key(b, a));
			if (t == owner.end() || u == owner.end()) {
				continue; // flipped away since it was pushed
			}
			const std::size_t ti = t->second, ui = u->second;
			const std::size_t c = after(triangles[ti], b), d = after(triangles[ui], a);
			if (!must_flip(p_points, a, b, c, d)) {
				continue;
			}
			if (budget-- == 0) {
				return false;
			}
			owner.erase(key(a, b));
			owner.erase(key(b, a));
			triangles[ti] = { a, d, c };
			triangles[ui] = { d, b, c };
			own(ti);
			own(ui);
			for (const auto &[p, q] : { std::pair{ a, d }, std::pair{ d, b }, std::pair{ b, c }, std::pair{ c, a } }) {
				push_diagonal(p, q, &stack);
			}
		}
		return true;
	}

	const std::vector<Triangle> &result() const { return triangles; }

private:
	std::size_t corners;
	std::vector<Triangle> triangles;
	std::unordered_map<std::uint64_t, std::size_t> owner;

	std::uint64_t key(std::size_t p_from, std::size_t p_to) const { return std::uint64_t(p_from) * corners + p_to; }

	void own(std::size_t p_triangle) {
		const Triangle &t = triangles[p_triangle];
		for (int i = 0; i < 3; ++i) {
			owner[key(t[i], t[(i + 1) % 3])] = p_triangle;
		}
	}

	// The corner after p_corner in the triangle's counter-clockwise order.
	static std::size_t after(const Triangle &p_triangle, std::size_t p_corner) {
		return p_triangle[0] == p_corner ? p_triangle[1] : p_triangle[1] == p_corner ? p_triangle[2] : p_triangle[0];
	}

	// Walls (consecutive corners) are constraints and never flip.
	void push_diagonal(std::size_t p_a, std::size_t p_b, std::vector<std::pair<std::size_t, std::size_t>> *r_stack) const {
		if ((p_a + 1) % corners != p_b && (p_b + 1) % corners != p_a) {
			r_stack->emplace_back(p_a, p_b);
		}
	}
};

// The first repeated point's indices, or false.
bool find_repeat(const std::vector<Point> &p_points, std::size_t *r_i, std::size_t *r_j) {
	std::vector<std::size_t> order(p_points.size());
	std::iota(order.begin(), order.end(), std::size_t(0));
	std::sort(order.begin(), order.end(), [&](std::size_t p_a, std::size_t p_b) {
		const CGAL::Comparison_result c = CGAL::compare_xy(p_points[p_a], p_points[p_b]);
		return c == CGAL::SMALLER || (c == CGAL::EQUAL && p_a < p_b);
	});
	for (std::size_t k = 1; k < order.size(); ++k) {
		if (p_points[order[k - 1]] == p_points[order[k]]) {
			*r_i = std::min(order[k - 1], order[k]);
			*r_j = std::max(order[k - 1], order[k]);
			return true;
		}
	}
	return false;
}

// Each triangle from its smallest corner, then the triangles sorted: an order that does not
// depend on the clipping and flipping sequence.
std::vector<std::size_t> canonical(std::vector<Triangle> p_triangles) {
	for (Triangle &t : p_triangles) {
		std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
	}
	std::sort(p_triangles.begin(), p_triangles.end());
	std::vector<std::size_t> flat;
	flat.reserve(3 * p_triangles.size());
	for (const Triangle &t : p_triangles) {
		flat.insert(flat.end(), t.begin(), t.end());
	}
	return flat;
}

// A quadrilateral's two triangles in the order and rotation CGAL's triangulation gave them: the
// synthetic living room (a rectangle) then renders as before, and the figures made with it stand.
std::vector<std::size_t> quad_as_cgal_gave(std::vector<std::size_t> p_canonical) {
	if (p_canonical == std::vector<std::size_t>{ 0, 1, 3, 1, 2, 3 }) {
		return { 3, 1, 2, 3, 0, 1 };
	}
	if (p_canonical == std::vector<std::size_t>{ 0, 1, 2, 0, 2, 3 }) {
		return { 0, 1, 2, 3, 0, 2 };
	}
	return p_canonical;
}

bool triangulate_unguarded(const std::vector<Vec2> &p_points, std::vector<std::size_t> *r_triangles, std::string *r_error) {
	const std::size_t n = p_points.size();
	if (n < 3) {
		*r_error = "floor triangulation needs at least 3 corners, got " + std::to_string(n);
		return false;
	}
	std::vector<Point> points;
	points.reserve(n);
	for (const Vec2 &p : p_points) {
		points.push_back(room_cgal::to_cgal(p));
	}
	std::size_t i = 0, j = 0;
	if (find_repeat(points, &i, &j)) {
		*r_error = "floor triangulation: corners " + std::to_string(i) + " and " + std::to_string(j) + " are the same point";
		return false;
	}
	std::vector<Triangle> triangles;
	if (!clip_ears(points, &triangles)) {
		*r_error = "floor triangulation found no ear to clip: the polygon is not simple and counter-clockwise";
		return false;
	}
	FlipMesh mesh(n, std::move(triangles));
	if (!mesh.make_delaunay(points)) {
		*r_error = "floor triangulation: the Delaunay flips did not settle";
		return false;
	}
	*r_triangles = canonical(mesh.result());
	if (n == 4) {
		*r_triangles = quad_as_cgal_gave(*r_triangles);
	}
	return true;
}

} // namespace

bool triangulate_polygon(const std::vector<Vec2> &p_points, std::vector<std::size_t> *r_triangles, std::string *r_error) {
	// CGAL's predicates throw on a failed precondition (NaN input); none may leave the core.
	try {
		return triangulate_unguarded(p_points, r_triangles, r_error);
	} catch (const std::exception &e) {
		*r_error = std::string("floor triangulation failed: ") + e.what();
		return false;
	}
}

} // namespace roomprobe
