#include "floorplan.h"

#include "room_cgal.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <utility>

namespace roomprobe {

namespace {

using room_cgal::Point;
using room_cgal::Segment;

// Shortest round-trip text for a double ("-1", "2.6", "nan"), for messages.
std::string format_number(double p_value) {
	char buffer[64];
	const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), p_value);
	return std::string(buffer, result.ptr);
}

std::string describe_edge(std::size_t p_edge, std::size_t p_count) {
	return "edge " + std::to_string(p_edge) + " (points " + std::to_string(p_edge) + "-" +
			std::to_string((p_edge + 1) % p_count) + ")";
}

FloorplanCheck fail(FloorplanCheck::Problem p_problem, std::string p_message) {
	FloorplanCheck check;
	check.ok = false;
	check.problem = p_problem;
	check.message = std::move(p_message);
	return check;
}

// Two edges sharing endpoint p_shared only meet elsewhere if they are collinear
// and the polygon turns back by 180 degrees.
bool folds_back(const Point &p_before, const Point &p_shared, const Point &p_after) {
	return CGAL::collinear(p_before, p_shared, p_after) &&
			!CGAL::collinear_are_ordered_along_line(p_before, p_shared, p_after);
}

// How two non-adjacent, intersecting edges meet, for the message.
const char *intersection_verb(const Segment &p_a, const Segment &p_b) {
	const CGAL::Orientation a0 = CGAL::orientation(p_a.source(), p_a.target(), p_b.source());
	const CGAL::Orientation a1 = CGAL::orientation(p_a.source(), p_a.target(), p_b.target());
	const CGAL::Orientation b0 = CGAL::orientation(p_b.source(), p_b.target(), p_a.source());
	const CGAL::Orientation b1 = CGAL::orientation(p_b.source(), p_b.target(), p_a.target());
	if (a0 == CGAL::COLLINEAR && a1 == CGAL::COLLINEAR) {
		// Collinear and intersecting: sharing more than one point means an overlap.
		const bool shares_length = p_a == p_b || p_a == p_b.opposite() ||
				CGAL::collinear_are_strictly_ordered_along_line(p_a.source(), p_b.source(), p_a.target()) ||
				CGAL::collinear_are_strictly_ordered_along_line(p_a.source(), p_b.target(), p_a.target()) ||
				CGAL::collinear_are_strictly_ordered_along_line(p_b.source(), p_a.source(), p_b.target()) ||
				CGAL::collinear_are_strictly_ordered_along_line(p_b.source(), p_a.target(), p_b.target());
		return shares_length ? "overlaps" : "touches";
	}
	if (a0 * a1 < 0 && b0 * b1 < 0) {
		return "crosses";
	}
	return "touches";
}

// O(n^2) scan naming the first offending edge pair; only run once CGAL has
// said the polygon is not simple, so its cost does not matter for valid rooms.
std::string find_intersection_message(const std::vector<Vec2> &p_points) {
	const std::size_t n = p_points.size();
	std::vector<Segment> edges;
	edges.reserve(n);
	for (std::size_t i = 0; i < n; ++i) {
		edges.emplace_back(room_cgal::to_cgal(p_points[i]), room_cgal::to_cgal(p_points[(i + 1) % n]));
	}
	for (std::size_t i = 0; i < n; ++i) {
		for (std::size_t j = i + 1; j < n; ++j) {
			const bool next = j == i + 1;
			const bool wraps = i == 0 && j == n - 1;
			bool bad = false;
			const char *verb = "folds back onto";
			if (next) {
				bad = folds_back(edges[i].source(), edges[i].target(), edges[j].target());
			} else if (wraps) {
				bad = folds_back(edges[j].source(), edges[i].source(), edges[i].target());
			} else if (CGAL::do_intersect(edges[i], edges[j])) {
				bad = true;
				verb = intersection_verb(edges[i], edges[j]);
			}
			if (bad) {
				return "floorplan " + describe_edge(i, n) + " " + verb + " " + describe_edge(j, n);
			}
		}
	}
	return "floorplan is not a simple polygon (its edges intersect)";
}

FloorplanCheck check_floorplan_unguarded(const Floorplan &p_floorplan) {
	using Problem = FloorplanCheck::Problem;
	const std::vector<Vec2> &points = p_floorplan.points;
	const std::size_t n = points.size();
	if (n > FLOORPLAN_MAX_POINTS) {
		return fail(Problem::TooManyPoints, "floorplan has " + std::to_string(n) + " points; at most " + std::to_string(FLOORPLAN_MAX_POINTS) +
						" are accepted (a room's corners, not a point cloud)");
	}

	for (std::size_t i = 0; i < n; ++i) {
		if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
			return fail(Problem::NonFinite, "floorplan point " + std::to_string(i) + " has a non-finite coordinate (" +
							format_number(points[i].x) + ", " + format_number(points[i].y) + ")");
		}
	}
	if (!std::isfinite(p_floorplan.ceiling_height_m)) {
		return fail(Problem::NonFinite, "ceiling height must be a finite number, got " + format_number(p_floorplan.ceiling_height_m));
	}
	if (n < 3) {
		return fail(Problem::TooFewPoints, "floorplan has " + std::to_string(n) + (n == 1 ? " point" : " points") +
						"; a room needs at least 3");
	}
	if (p_floorplan.ceiling_height_m <= 0.0) {
		return fail(Problem::CeilingNotPositive, "ceiling height must be above 0 m, got " + format_number(p_floorplan.ceiling_height_m));
	}
	for (std::size_t i = 0; i < n; ++i) {
		const Vec2 &a = points[i];
		const Vec2 &b = points[(i + 1) % n];
		if (a.x == b.x && a.y == b.y) {
			return fail(Problem::SelfIntersecting, "floorplan points " + std::to_string(i) + " and " +
							std::to_string((i + 1) % n) + " are the same point, so " + describe_edge(i, n) +
							" has zero length (repeated point)");
		}
	}

	const Point first = room_cgal::to_cgal(points[0]);
	const Point second = room_cgal::to_cgal(points[1]);
	bool all_collinear = true;
	for (std::size_t i = 2; i < n && all_collinear; ++i) {
		all_collinear = CGAL::collinear(first, second, room_cgal::to_cgal(points[i]));
	}
	if (all_collinear) {
		return fail(Problem::ZeroArea, "floorplan encloses zero area: all " + std::to_string(n) + " points lie on one line");
	}

	const room_cgal::Polygon polygon = room_cgal::to_polygon(points);
	if (!polygon.is_simple()) {
		return fail(Problem::SelfIntersecting, find_intersection_message(points));
	}
	// A simple polygon with non-collinear corners has non-zero area; this
	// guards against underflow for absurdly small rooms.
	if (polygon.area() == 0.0) {
		return fail(Problem::ZeroArea, "floorplan encloses zero area");
	}
	return FloorplanCheck();
}

} // namespace

FloorplanCheck check_floorplan(const Floorplan &p_floorplan) {
	// CGAL reports failures by throwing; the Godot side is usually built without
	// exceptions, so none may leave the core.
	try {
		return check_floorplan_unguarded(p_floorplan);
	} catch (const std::exception &e) {
		return fail(FloorplanCheck::Problem::SelfIntersecting, std::string("floorplan geometry check failed: ") + e.what());
	}
}

const char *floorplan_problem_summary(FloorplanCheck::Problem p_problem) {
	switch (p_problem) {
		case FloorplanCheck::Problem::None:
			return "The floorplan is valid";
		case FloorplanCheck::Problem::TooFewPoints:
			return "The floorplan has fewer than 3 points";
		case FloorplanCheck::Problem::SelfIntersecting:
			return "The floorplan is self-intersecting";
		case FloorplanCheck::Problem::ZeroArea:
			return "The floorplan encloses zero area";
		case FloorplanCheck::Problem::CeilingNotPositive:
			return "The ceiling is at or below the floor (ceiling height <= 0)";
		case FloorplanCheck::Problem::NonFinite:
			return "The floorplan or ceiling height is not a finite number";
		case FloorplanCheck::Problem::TooManyPoints:
			return "The floorplan has too many points";
	}
	return "The floorplan is invalid";
}

double floorplan_signed_area_m2(const Floorplan &p_floorplan) {
	return polygon_signed_area_m2(p_floorplan.points);
}

bool polygon_contains(const std::vector<Vec2> &p_points, const Vec2 &p_point) {
	bool inside = false;
	for (std::size_t i = 0, j = p_points.size() - 1; i < p_points.size(); j = i++) {
		const Vec2 &a = p_points[j];
		const Vec2 &b = p_points[i];
		if ((b.y > p_point.y) != (a.y > p_point.y) && p_point.x < (a.x - b.x) * (p_point.y - b.y) / (a.y - b.y) + b.x) {
			inside = !inside;
		}
	}
	return inside;
}

double polygon_signed_area_m2(const std::vector<Vec2> &p_points) {
	const std::vector<Vec2> &points = p_points;
	const std::size_t n = points.size();
	double twice_area = 0.0;
	for (std::size_t i = 0; i < n; ++i) {
		const Vec2 &a = points[i];
		const Vec2 &b = points[(i + 1) % n];
		twice_area += a.x * b.y - b.x * a.y;
	}
	return 0.5 * twice_area;
}

double floorplan_perimeter_m(const Floorplan &p_floorplan) {
	const std::vector<Vec2> &points = p_floorplan.points;
	const std::size_t n = points.size();
	double perimeter = 0.0;
	for (std::size_t i = 0; i < n && n >= 2; ++i) {
		const Vec2 &a = points[i];
		const Vec2 &b = points[(i + 1) % n];
		perimeter += std::hypot(b.x - a.x, b.y - a.y);
	}
	return perimeter;
}

bool is_counter_clockwise(const Floorplan &p_floorplan) {
	if (p_floorplan.points.size() < 3) {
		return false;
	}
	const room_cgal::Polygon polygon = room_cgal::to_polygon(p_floorplan.points);
	// CGAL's orientation() requires a simple polygon; fall back to the signed
	// area for anything else so that this never trips a CGAL precondition.
	try {
		if (polygon.is_simple()) {
			return polygon.orientation() == CGAL::COUNTERCLOCKWISE;
		}
	} catch (const std::exception &) {
		// Fall through to the plain signed area; keep exceptions inside the core.
	}
	return floorplan_signed_area_m2(p_floorplan) > 0.0;
}

Floorplan normalized(const Floorplan &p_floorplan) {
	Floorplan result = p_floorplan;
	if (result.points.size() >= 3 && !is_counter_clockwise(result)) {
		// Reverse everything after points[0] so the first corner stays first.
		std::reverse(result.points.begin() + 1, result.points.end());
	}
	return result;
}

double distance_outside_room_m(const Floorplan &p_floorplan, const Vec3 &p_point) {
	const std::vector<Vec2> &points = p_floorplan.points;
	const std::size_t n = points.size();
	// Inside the polygon by the crossing rule, and the distance to its nearest wall.
	const bool inside = n > 0 && polygon_contains(points, Vec2{ p_point.x, p_point.z });
	double nearest_sq = std::numeric_limits<double>::infinity();
	for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
		const Vec2 &a = points[j];
		const Vec2 &b = points[i];
		const double ex = b.x - a.x, ez = b.y - a.y;
		const double length_sq = ex * ex + ez * ez;
		const double t = length_sq > 0.0 ? std::clamp(((p_point.x - a.x) * ex + (p_point.z - a.y) * ez) / length_sq, 0.0, 1.0) : 0.0;
		const double dx = p_point.x - (a.x + t * ex), dz = p_point.z - (a.y + t * ez);
		nearest_sq = std::min(nearest_sq, dx * dx + dz * dz);
	}
	const double across = inside || n == 0 ? 0.0 : std::sqrt(nearest_sq);
	const double up = std::max({ 0.0, -p_point.y, p_point.y - p_floorplan.ceiling_height_m });
	return std::hypot(across, up);
}

} // namespace roomprobe
