#include "segment_arrangement.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <map>
#include <set>

namespace roomprobe {

namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Exact::Point_2;

struct XyLess {
	bool operator()(const Point &p_a, const Point &p_b) const { return CGAL::compare_xy(p_a, p_b) == CGAL::SMALLER; }
};

struct Segment {
	Point a, b;
};

// Adds to each segment's list the points where the other one meets it: a crossing (an exact
// construction), an end on the other segment, or the ends of a collinear overlap.
void add_meeting_points(const Segment &p_s, const Segment &p_t, std::vector<Point> *r_on_s, std::vector<Point> *r_on_t) {
	const CGAL::Orientation o1 = CGAL::orientation(p_s.a, p_s.b, p_t.a), o2 = CGAL::orientation(p_s.a, p_s.b, p_t.b);
	const CGAL::Orientation o3 = CGAL::orientation(p_t.a, p_t.b, p_s.a), o4 = CGAL::orientation(p_t.a, p_t.b, p_s.b);
	if (o1 == CGAL::COLLINEAR && o2 == CGAL::COLLINEAR) {
		for (const Point &p : { p_t.a, p_t.b }) {
			if (CGAL::collinear_are_ordered_along_line(p_s.a, p, p_s.b)) {
				r_on_s->push_back(p);
			}
		}
		for (const Point &p : { p_s.a, p_s.b }) {
			if (CGAL::collinear_are_ordered_along_line(p_t.a, p, p_t.b)) {
				r_on_t->push_back(p);
			}
		}
		return;
	}
	if (o1 * o2 > 0 || o3 * o4 > 0) {
		return; // both ends of one on the same side of the other
	}
	Point meet;
	if (o1 == CGAL::COLLINEAR || o2 == CGAL::COLLINEAR) {
		meet = o1 == CGAL::COLLINEAR ? p_t.a : p_t.b;
	} else if (o3 == CGAL::COLLINEAR || o4 == CGAL::COLLINEAR) {
		meet = o3 == CGAL::COLLINEAR ? p_s.a : p_s.b;
	} else {
		const Exact::Vector_2 d = p_s.b - p_s.a, e = p_t.b - p_t.a;
		meet = p_s.a + (CGAL::determinant(p_t.a - p_s.a, e) / CGAL::determinant(d, e)) * d;
	}
	r_on_s->push_back(meet);
	r_on_t->push_back(meet);
}

// The undirected edges (vertex index pairs, smaller first) and the vertices, exactly.
void split_segments(const std::vector<Segment> &p_segments, std::vector<Point> *r_points, std::set<std::pair<int, int>> *r_edges) {
	std::vector<std::vector<Point>> on(p_segments.size());
	for (size_t i = 0; i < p_segments.size(); ++i) {
		on[i] = { p_segments[i].a, p_segments[i].b };
		for (size_t j = 0; j < i; ++j) {
			add_meeting_points(p_segments[i], p_segments[j], &on[i], &on[j]);
		}
	}
	std::map<Point, int, XyLess> index;
	for (std::vector<Point> &points : on) {
		// Points on one segment are collinear: (x, y) order is their order along it.
		std::sort(points.begin(), points.end(), XyLess());
		points.erase(std::unique(points.begin(), points.end()), points.end());
		int previous = -1;
		for (const Point &p : points) {
			const auto [it, added] = index.emplace(p, int(r_points->size()));
			if (added) {
				r_points->push_back(p);
			}
			if (previous >= 0) {
				r_edges->insert(std::minmax(previous, it->second));
			}
			previous = it->second;
		}
	}
}

// Whether the direction from p_centre to p_a comes before the one to p_b, counter-clockwise from +x.
bool turns_before(const Point &p_centre, const Point &p_a, const Point &p_b) {
	const auto half = [&](const Point &p_p) {
		const CGAL::Comparison_result y = CGAL::compare_y(p_p, p_centre);
		return y == CGAL::LARGER || (y == CGAL::EQUAL && CGAL::compare_x(p_p, p_centre) == CGAL::LARGER) ? 0 : 1;
	};
	const int ha = half(p_a), hb = half(p_b);
	return ha != hb ? ha < hb : CGAL::orientation(p_centre, p_a, p_b) == CGAL::LEFT_TURN;
}

// next: around the target, the outgoing half-edge that comes clockwise right after the twin.
void link_next(const std::vector<Point> &p_points, SegmentArrangement *io_arrangement) {
	std::vector<SegmentArrangement::Halfedge> &halfedges = io_arrangement->halfedges;
	std::vector<std::vector<int>> outgoing(p_points.size());
	for (size_t h = 0; h < halfedges.size(); ++h) {
		outgoing[halfedges[h].source].push_back(int(h));
	}
	std::vector<size_t> slot(halfedges.size());
	for (size_t v = 0; v < outgoing.size(); ++v) {
		std::vector<int> &around = outgoing[v];
		std::sort(around.begin(), around.end(), [&](int p_a, int p_b) {
			return turns_before(p_points[v], p_points[halfedges[p_a].target], p_points[halfedges[p_b].target]);
		});
		for (size_t k = 0; k < around.size(); ++k) {
			slot[around[k]] = k;
		}
	}
	for (SegmentArrangement::Halfedge &h : halfedges) {
		const std::vector<int> &around = outgoing[h.target];
		h.next = around[(slot[h.twin] + around.size() - 1) % around.size()];
	}
}

// Each cycle of next is a face: bounded when it runs counter-clockwise (exact signed area).
void find_faces(const std::vector<Point> &p_points, SegmentArrangement *io_arrangement) {
	std::vector<SegmentArrangement::Halfedge> &halfedges = io_arrangement->halfedges;
	io_arrangement->faces.assign(1, SegmentArrangement::Face());
	for (size_t start = 0; start < halfedges.size(); ++start) {
		if (halfedges[start].face >= 0) {
			continue;
		}
		Exact::FT twice_area = 0;
		std::vector<int> cycle;
		for (int h = int(start); cycle.empty() || h != int(start); h = halfedges[h].next) {
			cycle.push_back(h);
			twice_area += CGAL::determinant(p_points[halfedges[h].source] - CGAL::ORIGIN, p_points[halfedges[h].target] - CGAL::ORIGIN);
		}
		int face = 0;
		if (CGAL::sign(twice_area) == CGAL::POSITIVE) {
			face = int(io_arrangement->faces.size());
			io_arrangement->faces.push_back({ int(start), true });
		}
		for (const int h : cycle) {
			halfedges[h].face = face;
		}
	}
}

} // namespace

SegmentArrangement arrange_segments(const std::vector<std::pair<Vec2, Vec2>> &p_segments) {
	std::vector<Segment> segments;
	for (const auto &[a, b] : p_segments) {
		const Point pa(a.x, a.y), pb(b.x, b.y);
		if (pa != pb) {
			segments.push_back({ pa, pb });
		}
	}
	std::vector<Point> points;
	std::set<std::pair<int, int>> edges;
	split_segments(segments, &points, &edges);

	SegmentArrangement arrangement;
	for (const Point &p : points) {
		arrangement.vertices.push_back({ CGAL::to_double(p.x()), CGAL::to_double(p.y()) });
	}
	for (const auto &[u, v] : edges) {
		const int h = int(arrangement.halfedges.size());
		arrangement.halfedges.push_back({ u, v, h + 1, -1, -1 });
		arrangement.halfedges.push_back({ v, u, h, -1, -1 });
	}
	link_next(points, &arrangement);
	find_faces(points, &arrangement);
	return arrangement;
}

std::vector<Vec2> face_polygon(const SegmentArrangement &p_arrangement, int p_face) {
	std::vector<Vec2> polygon;
	const int first = p_arrangement.faces[size_t(p_face)].halfedge;
	int edge = first;
	// At most one corner a half-edge: a broken next-chain cannot loop for ever.
	do {
		polygon.push_back(p_arrangement.vertices[size_t(p_arrangement.halfedges[size_t(edge)].source)]);
		edge = p_arrangement.halfedges[size_t(edge)].next;
	} while (edge != first && polygon.size() <= p_arrangement.halfedges.size());
	return polygon;
}

} // namespace roomprobe
