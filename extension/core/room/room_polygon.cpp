#include "room_polygon.h"

#include "segment_arrangement.h"
#include "wall_planes.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace roomprobe::room_planes {

namespace {

// A wall seen ending this close to a wall across it ends in that corner.
constexpr double CORNER_REACH_M = 0.3;

// A line n . p = d clipped to a box: false when it misses.
bool clip_line(const Vec2 &p_normal, double p_offset, const Vec2 &p_min, const Vec2 &p_max, Vec2 *r_a, Vec2 *r_b) {
	const Vec2 along = perp(p_normal);
	const Vec2 base = { p_normal.x * p_offset, p_normal.y * p_offset };
	double t0 = -1e9, t1 = 1e9;
	const double origin[2] = { base.x, base.y }, direction[2] = { along.x, along.y }, low[2] = { p_min.x, p_min.y }, high[2] = { p_max.x, p_max.y };
	for (int axis = 0; axis < 2; axis++) {
		if (std::abs(direction[axis]) < 1e-12) {
			if (origin[axis] < low[axis] || origin[axis] > high[axis]) {
				return false;
			}
			continue;
		}
		double a = (low[axis] - origin[axis]) / direction[axis], b = (high[axis] - origin[axis]) / direction[axis];
		if (a > b) {
			std::swap(a, b);
		}
		t0 = std::max(t0, a);
		t1 = std::min(t1, b);
	}
	if (t1 - t0 < 1e-6) {
		return false;
	}
	*r_a = { base.x + along.x * t0, base.y + along.y * t0 };
	*r_b = { base.x + along.x * t1, base.y + along.y * t1 };
	return true;
}

// Drops corners where the boundary runs straight on (the arrangement splits walls at every line).
std::vector<Vec2> drop_straight_corners(std::vector<Vec2> p_points) {
	bool changed = true;
	while (changed && p_points.size() > 3) {
		changed = false;
		for (size_t i = 0; i < p_points.size(); i++) {
			const Vec2 &a = p_points[(i + p_points.size() - 1) % p_points.size()], &b = p_points[i], &c = p_points[(i + 1) % p_points.size()];
			const Vec2 u = { b.x - a.x, b.y - a.y }, v = { c.x - b.x, c.y - b.y };
			const double lu = std::hypot(u.x, u.y), lv = std::hypot(v.x, v.y);
			if (lu < 1e-6 || lv < 1e-6 || std::abs(u.x * v.y - u.y * v.x) / (lu * lv) < 1e-3) {
				p_points.erase(p_points.begin() + long(i));
				changed = true;
				break;
			}
		}
	}
	return p_points;
}

// The share of the face's floor the sweep saw, or 1 when a camera position lies in it.
double face_seen(const std::vector<Vec2> &p_face, const FloorGrid &p_grid, const std::vector<Vec2> &p_cameras) {
	for (const Vec2 &camera : p_cameras) {
		if (polygon_contains(p_face, camera)) {
			return 1.0;
		}
	}
	Vec2 low = p_face.front(), high = p_face.front();
	for (const Vec2 &p : p_face) {
		low = { std::min(low.x, p.x), std::min(low.y, p.y) };
		high = { std::max(high.x, p.x), std::max(high.y, p.y) };
	}
	size_t total = 0, seen = 0;
	for (double y = low.y + 0.5 * p_grid.cell; y < high.y; y += p_grid.cell) {
		for (double x = low.x + 0.5 * p_grid.cell; x < high.x; x += p_grid.cell) {
			if (polygon_contains(p_face, { x, y })) {
				total++;
				seen += p_grid.at({ x, y }) ? 1 : 0;
			}
		}
	}
	return total == 0 ? 0.0 : double(seen) / double(total);
}

// The lines that may bound the room, clipped to a box around everything seen: the walls' lines
// and the ends of what was seen of them (where the room may end: a partition's end).
std::vector<std::pair<Vec2, Vec2>> room_lines(const std::vector<WallEstimate> &p_walls, const FloorGrid &p_grid) {
	struct Line {
		Vec2 normal;
		double offset;
	};
	std::vector<Line> lines;
	auto add_line = [&](const Vec2 &p_normal, double p_offset) {
		for (const Line &line : lines) { // the same line (either orientation) is inserted once
			const double c = dot2(line.normal, p_normal);
			if (std::abs(c) > std::cos(1.0 * DEG) && std::abs(line.offset - c * p_offset) < 0.05) {
				return;
			}
		}
		lines.push_back({ p_normal, p_offset });
	};
	for (const WallEstimate &wall : p_walls) {
		add_line(wall.normal, wall.offset_m);
	}
	// An end near a wall across it is that corner, seen short of it (something stood in the
	// corner): the walls' own lines make the corner.
	for (const WallEstimate &wall : p_walls) {
		for (const double end : { wall.from_m, wall.to_m }) {
			const Vec2 point = { wall.normal.x * wall.offset_m + perp(wall.normal).x * end, wall.normal.y * wall.offset_m + perp(wall.normal).y * end };
			const bool near_wall = std::any_of(p_walls.begin(), p_walls.end(), [&](const WallEstimate &p_other) {
				return std::abs(dot2(p_other.normal, wall.normal)) < std::cos(5.0 * DEG) && std::abs(dot2(p_other.normal, point) - p_other.offset_m) < CORNER_REACH_M;
			});
			if (!near_wall) {
				add_line(perp(wall.normal), end);
			}
		}
	}
	Vec2 low = { p_grid.origin.x, p_grid.origin.y }, high = { p_grid.origin.x + p_grid.cell * p_grid.width, p_grid.origin.y + p_grid.cell * p_grid.height };
	for (const WallEstimate &wall : p_walls) {
		for (const double t : { wall.from_m, wall.to_m }) {
			const Vec2 p = { wall.normal.x * wall.offset_m + perp(wall.normal).x * t, wall.normal.y * wall.offset_m + perp(wall.normal).y * t };
			low = { std::min(low.x, p.x), std::min(low.y, p.y) };
			high = { std::max(high.x, p.x), std::max(high.y, p.y) };
		}
	}
	low = { low.x - 1.0, low.y - 1.0 };
	high = { high.x + 1.0, high.y + 1.0 };
	std::vector<std::pair<Vec2, Vec2>> segments;
	for (const Line &line : lines) {
		Vec2 a, b;
		if (clip_line(line.normal, line.offset, low, high, &a, &b)) {
			segments.emplace_back(a, b);
		}
	}
	return segments;
}

// A face whose floor stayed hidden (a sofa against the wall, the cut of a partition's seen end
// across it) is inside too when it opens onto the room, no wall between, and on its other
// sides the sweep saw walls facing into it, at least half their length and a metre: the camera
// looked across it at them. A face behind a wall seen from the room (a partition's inside), or
// bounded by walls never seen, stays out.
bool hidden_face_inside(const SegmentArrangement &p_arrangement, int p_face, const std::vector<uint8_t> &p_inside, const std::vector<WallEstimate> &p_walls) {
	double open_m = 0.0, outer_m = 0.0, outer_walls_m = 0.0;
	bool behind_wall = false;
	const int first = p_arrangement.faces[p_face].halfedge;
	int edge = first;
	do { // counter-clockwise: the face on the left
		const SegmentArrangement::Halfedge &h = p_arrangement.halfedges[edge];
		const Vec2 a = p_arrangement.vertices[h.source], b = p_arrangement.vertices[h.target];
		const double length = std::hypot(b.x - a.x, b.y - a.y);
		if (p_inside[p_arrangement.halfedges[h.twin].face]) {
			const double wall = wall_cover(a, b, false, p_walls);
			behind_wall = behind_wall || wall > 0.2; // the room sees a wall's face here: F is behind it (inside a partition)
			open_m += length * (1.0 - wall);
		} else {
			outer_m += length;
			outer_walls_m += length * wall_cover(a, b, true, p_walls);
		}
		edge = h.next;
	} while (edge != first);
	return !behind_wall && open_m >= 0.3 && outer_walls_m >= 1.0 && outer_walls_m >= 0.5 * outer_m;
}

// The largest region's boundary: half-edges with an inside face on their left and an outside one
// on their right, walked face by face: after a boundary half-edge, the next one turns around its
// target through the inside faces (so two regions meeting at one corner are walked apart).
std::vector<Vec2> largest_boundary(const SegmentArrangement &p_arrangement, const std::vector<uint8_t> &p_inside) {
	const std::vector<SegmentArrangement::Halfedge> &halfedges = p_arrangement.halfedges;
	auto on_boundary = [&](int p_edge) { return p_inside[halfedges[p_edge].face] && !p_inside[halfedges[halfedges[p_edge].twin].face]; };
	std::vector<uint8_t> walked(halfedges.size(), 0);
	std::vector<Vec2> best;
	double best_area = 0.0;
	for (int start = 0; start < int(halfedges.size()); ++start) {
		if (!on_boundary(start) || walked[start]) {
			continue;
		}
		std::vector<Vec2> loop;
		int edge = start;
		do {
			walked[edge] = 1;
			loop.push_back(p_arrangement.vertices[halfedges[edge].source]);
			int next = halfedges[edge].next;
			for (size_t turns = 0; !on_boundary(next) && turns < halfedges.size(); turns++) {
				next = halfedges[halfedges[next].twin].next;
			}
			edge = next;
		} while (edge != start && !walked[edge]);
		const double area = loop.size() >= 3 ? polygon_signed_area_m2(loop) : 0.0;
		if (area > best_area) {
			best_area = area;
			best = loop;
		}
	}
	return best;
}

// The corners (and so the walls) numbered from the one before the lowest-leftmost (x within 1 mm,
// then z): the order CGAL's arrangement, used before, gave the rooms of the tests.
std::vector<Vec2> numbered_from_left(std::vector<Vec2> p_loop) {
	if (p_loop.empty()) {
		return p_loop;
	}
	double left = p_loop.front().x;
	for (const Vec2 &p : p_loop) {
		left = std::min(left, p.x);
	}
	size_t lowest = p_loop.size();
	for (size_t i = 0; i < p_loop.size(); ++i) {
		if (p_loop[i].x <= left + 1e-3 && (lowest == p_loop.size() || p_loop[i].y < p_loop[lowest].y)) {
			lowest = i;
		}
	}
	std::rotate(p_loop.begin(), p_loop.begin() + long((lowest + p_loop.size() - 1) % p_loop.size()), p_loop.end());
	return p_loop;
}

} // namespace

// The share of the segment a to b covered by a wall on its line facing its left side (or its
// right, when p_left is false): what the sweep saw there as a wall, seen from that side.
double wall_cover(const Vec2 &p_a, const Vec2 &p_b, bool p_left, const std::vector<WallEstimate> &p_walls) {
	const double length = std::hypot(p_b.x - p_a.x, p_b.y - p_a.y);
	if (!(length > 0.0)) {
		return 0.0;
	}
	const Vec2 left = { -(p_b.y - p_a.y) / length, (p_b.x - p_a.x) / length };
	const Vec2 facing = p_left ? left : Vec2{ -left.x, -left.y };
	double cover = 0.0;
	for (const WallEstimate &wall : p_walls) {
		if (dot2(wall.normal, facing) > std::cos(2.0 * DEG) && std::abs(dot2(wall.normal, p_a) - wall.offset_m) < 0.05) {
			const double ta = dot2(perp(wall.normal), p_a), tb = dot2(perp(wall.normal), p_b);
			const double overlap = std::min(std::max(ta, tb), wall.to_m) - std::max(std::min(ta, tb), wall.from_m);
			cover = std::max(cover, std::clamp(overlap / length, 0.0, 1.0));
		}
	}
	return cover;
}

std::vector<Vec2> room_polygon(const std::vector<WallEstimate> &p_walls, const FloorGrid &p_grid, const std::vector<Vec2> &p_cameras,
		const RoomEstimationOptions &p_options) {
	const SegmentArrangement arrangement = arrange_segments(room_lines(p_walls, p_grid));
	const int faces = int(arrangement.faces.size());
	std::vector<uint8_t> inside(faces, 0); // the unbounded face (0) stays out
	for (int face = 1; face < faces; ++face) {
		inside[face] = face_seen(face_polygon(arrangement, face), p_grid, p_cameras) >= p_options.min_floor_seen;
	}
	for (bool grew = true; grew;) {
		grew = false;
		for (int face = 1; face < faces; ++face) {
			if (!inside[face] && hidden_face_inside(arrangement, face, inside, p_walls)) {
				inside[face] = 1;
				grew = true;
			}
		}
	}
	const std::vector<Vec2> best = numbered_from_left(largest_boundary(arrangement, inside));
	return best.empty() ? best : drop_straight_corners(best);
}

} // namespace roomprobe::room_planes
