// Floorplan validation and orientation (paper §4.1 coarse room input).

#include "room/floorplan.h"
#include "room/reference_rooms.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

using Problem = FloorplanCheck::Problem;

Floorplan make_floorplan(std::vector<Vec2> p_points, double p_ceiling_m = 2.5) {
	Floorplan floorplan;
	floorplan.points = std::move(p_points);
	floorplan.ceiling_height_m = p_ceiling_m;
	return floorplan;
}

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

} // namespace

TEST_CASE("reference rooms are valid, counter-clockwise and have the documented size") {
	struct Expected {
		Floorplan floorplan;
		size_t corners;
		double area_m2;
		double perimeter_m;
		double ceiling_m;
	};
	const Expected rooms[] = {
		{ figure4_two_rooms(), 8, 8.0 * 4.5 - 0.12 * 3.0, 2 * 8.0 + 2 * 4.5 + 2 * 3.0, 2.6 },
		{ living_room(), 4, 20.0, 18.0, 2.5 },
		{ l_shaped_room(), 6, 24.0, 22.0, 2.4 },
	};
	for (const Expected &room : rooms) {
		const FloorplanCheck check = check_floorplan(room.floorplan);
		CHECK(check.ok);
		CHECK(check.problem == Problem::None);
		CHECK(check.message.empty());
		CHECK(room.floorplan.points.size() == room.corners);
		CHECK(is_counter_clockwise(room.floorplan));
		CHECK(floorplan_signed_area_m2(room.floorplan) == doctest::Approx(room.area_m2).epsilon(1e-12));
		CHECK(floorplan_perimeter_m(room.floorplan) == doctest::Approx(room.perimeter_m).epsilon(1e-12));
		CHECK(room.floorplan.ceiling_height_m == room.ceiling_m);
	}
}

TEST_CASE("figure 4 floorplan is non-convex: the partition makes reflex corners") {
	const Floorplan floorplan = figure4_two_rooms();
	const auto &p = floorplan.points;
	int reflex = 0;
	for (size_t i = 0; i < p.size(); ++i) {
		const Vec2 &a = p[(i + p.size() - 1) % p.size()];
		const Vec2 &b = p[i];
		const Vec2 &c = p[(i + 1) % p.size()];
		const double turn = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
		reflex += turn < 0.0 ? 1 : 0;
	}
	CHECK(reflex == 2); // The two corners where the partition meets the wall.
}

TEST_CASE("a bow-tie is self-intersecting and the message names the crossing edges") {
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 2, 2 }, { 2, 0 }, { 0, 2 } }));
	CHECK_FALSE(check.ok);
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 0 (points 0-1) crosses edge 2 (points 2-3)");
}

TEST_CASE("a crossing involving the closing edge names it with its wrap-around points") {
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 4, 0 }, { 4, 4 }, { 6, 4 }, { 6, 3 } }));
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 1 (points 1-2) crosses edge 4 (points 4-0)");
}

TEST_CASE("a corner touching another wall is self-intersecting (touches)") {
	// Point 3 lies on edge 0.
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 4, 0 }, { 4, 2 }, { 2, 0 }, { 0, 2 } }));
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 0 (points 0-1) touches edge 2 (points 2-3)");
}

TEST_CASE("a wall that folds back onto the previous one is self-intersecting") {
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 2, 0 }, { 1, 0 }, { 1, 1 } }));
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 0 (points 0-1) folds back onto edge 1 (points 1-2)");
}

TEST_CASE("too few points") {
	const FloorplanCheck two = check_floorplan(make_floorplan({ { 0, 0 }, { 1, 0 } }));
	CHECK_FALSE(two.ok);
	CHECK(two.problem == Problem::TooFewPoints);
	CHECK(two.message == "floorplan has 2 points; a room needs at least 3");
	const FloorplanCheck none = check_floorplan(make_floorplan({}));
	CHECK(none.problem == Problem::TooFewPoints);
	CHECK(contains(none.message, "0 points"));
	const FloorplanCheck one = check_floorplan(make_floorplan({ { 1, 1 } }));
	CHECK(one.message == "floorplan has 1 point; a room needs at least 3");
}

TEST_CASE("too many points are refused before anything else is checked") {
	// A 2-m circle of FLOORPLAN_MAX_POINTS points is a room; one more is refused, and a 100000-point
	// one (which once held the editor for minutes) at once, whatever its coordinates hold.
	auto circle = [](size_t p_count) {
		std::vector<Vec2> points;
		for (size_t i = 0; i < p_count; i++) {
			const double a = 2.0 * 3.14159265358979 * double(i) / double(p_count);
			points.push_back({ 2.0 * std::cos(a), 2.0 * std::sin(a) });
		}
		return make_floorplan(points);
	};
	CHECK(check_floorplan(circle(FLOORPLAN_MAX_POINTS)).ok);
	const FloorplanCheck over = check_floorplan(circle(FLOORPLAN_MAX_POINTS + 1));
	CHECK(over.problem == Problem::TooManyPoints);
	CHECK(over.message == "floorplan has 1025 points; at most 1024 are accepted (a room's corners, not a point cloud)");
	Floorplan huge = circle(100000);
	huge.points[5].x = std::nan("");
	CHECK(check_floorplan(huge).problem == Problem::TooManyPoints);
	CHECK(std::string(floorplan_problem_summary(Problem::TooManyPoints)) == "The floorplan has too many points");
}

TEST_CASE("collinear points enclose zero area") {
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 1, 0 }, { 3, 0 } }));
	CHECK_FALSE(check.ok);
	CHECK(check.problem == Problem::ZeroArea);
	CHECK(contains(check.message, "zero area"));
	const FloorplanCheck diagonal = check_floorplan(make_floorplan({ { 0, 0 }, { 1, 1 }, { 3, 3 }, { 2, 2 } }));
	CHECK(diagonal.problem == Problem::ZeroArea);
}

TEST_CASE("the ceiling must be above the floor") {
	Floorplan floorplan = living_room();
	floorplan.ceiling_height_m = 0.0;
	FloorplanCheck check = check_floorplan(floorplan);
	CHECK_FALSE(check.ok);
	CHECK(check.problem == Problem::CeilingNotPositive);
	CHECK(check.message == "ceiling height must be above 0 m, got 0");

	floorplan.ceiling_height_m = -1.0;
	check = check_floorplan(floorplan);
	CHECK(check.problem == Problem::CeilingNotPositive);
	CHECK(check.message == "ceiling height must be above 0 m, got -1");
}

TEST_CASE("non-finite numbers are rejected first") {
	Floorplan floorplan = living_room();
	floorplan.points[1].y = std::numeric_limits<double>::quiet_NaN();
	FloorplanCheck check = check_floorplan(floorplan);
	CHECK_FALSE(check.ok);
	CHECK(check.problem == Problem::NonFinite);
	CHECK(contains(check.message, "point 1"));
	CHECK(contains(check.message, "non-finite"));
	CHECK(contains(check.message, "nan"));

	floorplan = living_room();
	floorplan.ceiling_height_m = std::numeric_limits<double>::infinity();
	check = check_floorplan(floorplan);
	CHECK(check.problem == Problem::NonFinite);
	CHECK(contains(check.message, "ceiling height"));

	// Also wins over other problems, since nothing else can be judged with a NaN.
	check = check_floorplan(make_floorplan({ { 0, std::nan("") }, { 1, 0 } }, -1.0));
	CHECK(check.problem == Problem::NonFinite);
}

TEST_CASE("repeated consecutive points make a zero-length wall") {
	Floorplan floorplan = living_room();
	floorplan.points.insert(floorplan.points.begin() + 2, floorplan.points[2]);
	FloorplanCheck check = check_floorplan(floorplan);
	CHECK_FALSE(check.ok);
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(contains(check.message, "points 2 and 3 are the same point"));
	CHECK(contains(check.message, "zero length"));

	// A common slip: closing the polygon by repeating the first point.
	floorplan = living_room();
	floorplan.points.push_back(floorplan.points[0]);
	check = check_floorplan(floorplan);
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(contains(check.message, "points 4 and 0 are the same point"));
}

TEST_CASE("a repeated non-consecutive point is self-intersecting") {
	// Two squares sharing corner (1, 1).
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 1, 0 }, { 1, 1 }, { 2, 1 }, { 2, 2 }, { 1, 2 }, { 1, 1 }, { 0, 1 } }));
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 1 (points 1-2) touches edge 5 (points 5-6)");
}

TEST_CASE("collinear walls that overlap are reported as overlapping") {
	// Edge 4 runs back from (5, 0) to (2, 0), along the end of edge 0.
	const FloorplanCheck check = check_floorplan(make_floorplan({ { 0, 0 }, { 4, 0 }, { 4, 2 }, { 5, 2 }, { 5, 0 }, { 2, 0 }, { 0, 1 } }));
	CHECK(check.problem == Problem::SelfIntersecting);
	CHECK(check.message == "floorplan edge 0 (points 0-1) overlaps edge 4 (points 4-5)");
}

TEST_CASE("a corner in the middle of a straight wall is allowed") {
	const Floorplan floorplan = make_floorplan({ { 0, 0 }, { 2, 0 }, { 4, 0 }, { 4, 3 }, { 0, 3 } });
	CHECK(check_floorplan(floorplan).ok);
	CHECK(floorplan_signed_area_m2(floorplan) == doctest::Approx(12.0));
}

TEST_CASE("clockwise floorplans are normalized to counter-clockwise, keeping point 0 first") {
	Floorplan clockwise = l_shaped_room();
	std::reverse(clockwise.points.begin(), clockwise.points.end());
	CHECK(check_floorplan(clockwise).ok); // Either orientation is valid input.
	CHECK_FALSE(is_counter_clockwise(clockwise));
	CHECK(floorplan_signed_area_m2(clockwise) == doctest::Approx(-24.0));

	const Floorplan result = normalized(clockwise);
	CHECK(is_counter_clockwise(result));
	CHECK(floorplan_signed_area_m2(result) == doctest::Approx(24.0));
	CHECK(result.ceiling_height_m == clockwise.ceiling_height_m);
	REQUIRE(result.points.size() == clockwise.points.size());
	const size_t n = clockwise.points.size();
	for (size_t i = 0; i < n; ++i) {
		const Vec2 &expected = clockwise.points[(n - i) % n];
		CHECK(result.points[i].x == expected.x);
		CHECK(result.points[i].y == expected.y);
	}

	// Already counter-clockwise: unchanged.
	const Floorplan same = normalized(l_shaped_room());
	for (size_t i = 0; i < n; ++i) {
		CHECK(same.points[i].x == l_shaped_room().points[i].x);
		CHECK(same.points[i].y == l_shaped_room().points[i].y);
	}
}

TEST_CASE("problem names") {
	CHECK(std::string(floorplan_problem_summary(Problem::SelfIntersecting)).find("self-intersecting") != std::string::npos);
	CHECK(std::string(floorplan_problem_summary(Problem::TooFewPoints)).find("fewer than 3 points") != std::string::npos);
	CHECK(std::string(floorplan_problem_summary(Problem::ZeroArea)).find("zero area") != std::string::npos);
	CHECK(std::string(floorplan_problem_summary(Problem::CeilingNotPositive)).find("at or below") != std::string::npos);
}
