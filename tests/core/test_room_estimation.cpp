// The room without a tape measure (issue #18, room/room_estimation.h): the world frame, the
// floorplan and the ceiling from a dense surface, the ceiling and unseen walls from the fisheye,
// and a given floorplan registered. The surfaces are built from known rooms, seen from an unknown
// frame (turned, tilted, moved), as marching cubes would give them: triangles facing free space.

#include "room/reference_rooms.h"
#include "room/room_estimation.h"
#include "room/room_from_sweep.h"
#include "slam/marching_cubes.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"

#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

constexpr double CELL_M = 0.05; // triangle size of walls and furniture
constexpr double FLOOR_CELL_M = 0.02; // ... and of the floor, where the room's extent is read

// A rectangle corner + a u + b v, split into cells, its triangles facing p_normal.
void add_quad(TriangleMesh *r_mesh, const glm::dvec3 &p_corner, glm::dvec3 p_u, glm::dvec3 p_v, const glm::dvec3 &p_normal, double p_cell_m = CELL_M) {
	if (glm::dot(glm::cross(p_u, p_v), p_normal) < 0.0) {
		std::swap(p_u, p_v);
	}
	const int nu = std::max(1, int(std::ceil(glm::length(p_u) / p_cell_m - 1e-9))), nv = std::max(1, int(std::ceil(glm::length(p_v) / p_cell_m - 1e-9)));
	for (int i = 0; i < nu; i++) {
		for (int j = 0; j < nv; j++) {
			const glm::dvec3 a = p_corner + p_u * (double(i) / nu) + p_v * (double(j) / nv);
			const glm::dvec3 du = p_u / double(nu), dv = p_v / double(nv);
			const uint32_t base = uint32_t(r_mesh->vertices.size());
			for (const glm::dvec3 &p : { a, a + du, a + du + dv, a + dv }) {
				r_mesh->vertices.emplace_back(glm::vec3(p));
				r_mesh->normals.emplace_back(glm::vec3(p_normal));
			}
			r_mesh->indices.insert(r_mesh->indices.end(), { base, base + 1, base + 2, base, base + 2, base + 3 });
		}
	}
}

struct RoomSurface {
	bool floor = true;
	double wall_seen_m = 1.5; // the walls seen up to this height (a camera at 1.45 m looking down)
	bool ceiling = false;
	std::vector<size_t> walls; // the floorplan edges seen (empty: all)
};

// The surface of a floorplan's room in world coordinates (floor cells inside the polygon).
TriangleMesh room_mesh_of(const Floorplan &p_plan, const RoomSurface &p_what) {
	TriangleMesh mesh;
	const size_t n = p_plan.points.size();
	double min_x = 1e9, max_x = -1e9, min_z = 1e9, max_z = -1e9;
	for (const Vec2 &p : p_plan.points) {
		min_x = std::min(min_x, p.x), max_x = std::max(max_x, p.x), min_z = std::min(min_z, p.y), max_z = std::max(max_z, p.y);
	}
	for (double x = min_x; x < max_x - 1e-9; x += FLOOR_CELL_M) {
		for (double z = min_z; z < max_z - 1e-9; z += FLOOR_CELL_M) {
			if (polygon_contains(p_plan.points, { x + 0.5 * FLOOR_CELL_M, z + 0.5 * FLOOR_CELL_M })) {
				if (p_what.floor) {
					add_quad(&mesh, { x, 0.0, z }, { FLOOR_CELL_M, 0.0, 0.0 }, { 0.0, 0.0, FLOOR_CELL_M }, { 0.0, 1.0, 0.0 }, FLOOR_CELL_M);
				}
				if (p_what.ceiling) {
					add_quad(&mesh, { x, p_plan.ceiling_height_m, z }, { FLOOR_CELL_M, 0.0, 0.0 }, { 0.0, 0.0, FLOOR_CELL_M }, { 0.0, -1.0, 0.0 }, FLOOR_CELL_M);
				}
			}
		}
	}
	const bool ccw = floorplan_signed_area_m2(p_plan) > 0.0;
	for (size_t i = 0; i < n; i++) {
		if (!p_what.walls.empty() && std::find(p_what.walls.begin(), p_what.walls.end(), i) == p_what.walls.end()) {
			continue;
		}
		const Vec2 &a = p_plan.points[i], &b = p_plan.points[(i + 1) % n];
		const glm::dvec3 along(b.x - a.x, 0.0, b.y - a.y);
		const glm::dvec3 inward = glm::normalize(ccw ? glm::dvec3(-along.z, 0.0, along.x) : glm::dvec3(along.z, 0.0, -along.x));
		add_quad(&mesh, { a.x, 0.0, a.y }, along, { 0.0, p_what.ceiling ? p_plan.ceiling_height_m : p_what.wall_seen_m, 0.0 }, inward);
	}
	return mesh;
}

// A box standing on the floor (a table, a wardrobe): its sides and top.
void add_box(TriangleMesh *r_mesh, const glm::dvec3 &p_min, const glm::dvec3 &p_max) {
	const glm::dvec3 size = p_max - p_min;
	add_quad(r_mesh, p_min, { 0.0, size.y, 0.0 }, { 0.0, 0.0, size.z }, { -1.0, 0.0, 0.0 });
	add_quad(r_mesh, { p_max.x, p_min.y, p_min.z }, { 0.0, size.y, 0.0 }, { 0.0, 0.0, size.z }, { 1.0, 0.0, 0.0 });
	add_quad(r_mesh, p_min, { size.x, 0.0, 0.0 }, { 0.0, size.y, 0.0 }, { 0.0, 0.0, -1.0 });
	add_quad(r_mesh, { p_min.x, p_min.y, p_max.z }, { size.x, 0.0, 0.0 }, { 0.0, size.y, 0.0 }, { 0.0, 0.0, 1.0 });
	add_quad(r_mesh, { p_min.x, p_max.y, p_min.z }, { size.x, 0.0, 0.0 }, { 0.0, 0.0, size.z }, { 0.0, 1.0, 0.0 });
}

// The unknown frame the dense model lives in: turned 30 degrees about up, tilted 3 degrees,
// moved (as the first camera's frame would be).
Pose model_from_world() {
	Pose pose;
	pose.rotation = glm::angleAxis(glm::radians(3.0), glm::normalize(glm::dvec3(1.0, 0.0, 0.4))) * glm::angleAxis(glm::radians(30.0), glm::dvec3(0.0, 1.0, 0.0));
	pose.translation = glm::dvec3(-1.2, 1.4, 0.7);
	return pose;
}

struct Estimated {
	RoomEstimate estimate;
	RoomComparison comparison;
	std::vector<SurfaceSample> world_samples; // in the estimated world
};

Estimated estimate_from(const TriangleMesh &p_world_mesh, const Floorplan &p_truth, const std::vector<glm::dvec3> &p_cameras_world) {
	const Pose model = model_from_world();
	const std::vector<SurfaceSample> samples = transform_samples(surface_samples(p_world_mesh), model);
	std::vector<glm::dvec3> cameras;
	for (const glm::dvec3 &c : p_cameras_world) {
		cameras.push_back(transform_point(model, c));
	}
	// The hint: the fisheye's axis, 6 degrees off up (a hand-held rig is not level).
	const glm::dvec3 hint = model.rotation * (glm::angleAxis(glm::radians(6.0), glm::dvec3(0.0, 0.0, 1.0)) * glm::dvec3(0.0, 1.0, 0.0));
	Estimated out;
	out.estimate = estimate_room(samples, hint, cameras);
	out.comparison = compare_rooms(out.estimate.floorplan, out.estimate.world_from_model, p_truth, inverse(model));
	out.world_samples = transform_samples(samples, out.estimate.world_from_model);
	return out;
}

// Tolerances: the surfaces lie exactly on the true planes, so what is left is how the planes are
// binned and fitted (1 cm bins, means of thousands of triangle centres): a millimetre or two.
constexpr double CORNER_TOLERANCE_M = 0.01;
constexpr double UP_TOLERANCE_DEG = 0.05;

} // namespace

TEST_CASE("room estimation: a non-convex room with a table, from an unknown frame, to its corners, up and ceiling") {
	const Floorplan truth = l_shaped_room(); // 6 x 5 m less a 3 x 2 m corner, ceiling 2.4 m
	RoomSurface seen;
	seen.ceiling = true;
	TriangleMesh mesh = room_mesh_of(truth, seen);
	add_box(&mesh, { 1.5, 0.0, 1.0 }, { 2.7, 0.75, 1.8 }); // a table: its sides face the room too
	const Estimated result = estimate_from(mesh, truth, { { 1.5, 1.45, 2.5 }, { 4.5, 1.45, 1.5 } });
	CAPTURE(result.estimate.message);
	REQUIRE(result.estimate.state == RoomEstimateState::Complete);
	CHECK(result.estimate.manhattan);
	CHECK(result.estimate.ceiling_source == "dense model");
	CHECK(result.comparison.corners == 6);
	CHECK(result.comparison.corner_error_max_m <= CORNER_TOLERANCE_M);
	CHECK(result.comparison.ceiling_error_m <= CORNER_TOLERANCE_M);
	CHECK(result.comparison.up_error_deg <= UP_TOLERANCE_DEG);
	CHECK(check_floorplan(result.estimate.floorplan).ok);
	for (const double confidence : result.estimate.edge_confidence) {
		CHECK(confidence > 0.9);
	}
	// The world: y = 0 on the floor, the floorplan at the origin's corner, axes along the walls.
	for (const Vec2 &p : result.estimate.floorplan.points) {
		CHECK((std::abs(p.x) < 1e-6 || std::abs(p.x - 3.0) < CORNER_TOLERANCE_M || std::abs(p.x - 6.0) < CORNER_TOLERANCE_M ||
				std::abs(p.y) < 1e-6 || std::abs(p.y - 3.0) < CORNER_TOLERANCE_M || std::abs(p.y - 5.0) < CORNER_TOLERANCE_M));
	}
}

TEST_CASE("room estimation: a partition counts as a wall, and a wardrobe's front does not; no ceiling seen is said") {
	const Floorplan truth = figure4_two_rooms(); // 8 x 4.5 m with a 12 cm partition 3 m deep
	TriangleMesh mesh = room_mesh_of(truth, RoomSurface());
	add_box(&mesh, { 0.05, 0.0, 3.7 }, { 0.65, 2.1, 4.45 }); // a wardrobe in the corner, 75 cm wide
	const Estimated result = estimate_from(mesh, truth, { { 2.0, 1.45, 2.0 }, { 6.0, 1.45, 2.0 } });
	CAPTURE(result.estimate.message);
	REQUIRE(result.estimate.state == RoomEstimateState::Partial);
	CHECK(result.estimate.message.find("the ceiling was not in the dense model") != std::string::npos);
	CHECK(result.estimate.floorplan.ceiling_height_m == 0.0);
	CHECK(result.comparison.corners == truth.points.size());
	CHECK(result.comparison.corner_error_max_m <= CORNER_TOLERANCE_M);
	CHECK(result.comparison.up_error_deg <= UP_TOLERANCE_DEG);
}

TEST_CASE("room estimation: floor hidden behind a sofa is room when the wall behind it was seen; not when it was not") {
	// The living room (5 x 4 m). A sofa along the wall z = 4 (its own surface left out: a sofa's
	// front can pass for a wall when nothing stands behind it) hides the floor from z = 3.2 on,
	// and the sofa's end hides the side wall x = 0 there: that wall is seen only to z = 3.2, and
	// its seen end cuts the floor across at z = 3.2, leaving a strip where no floor was seen.
	const Floorplan truth = living_room();
	auto sweep = [&](bool p_back_wall_seen) {
		TriangleMesh mesh;
		for (double x = 0.0; x < 5.0 - 1e-9; x += FLOOR_CELL_M) {
			add_quad(&mesh, { x, 0.0, 0.0 }, { FLOOR_CELL_M, 0.0, 0.0 }, { 0.0, 0.0, 3.2 }, { 0.0, 1.0, 0.0 }, FLOOR_CELL_M);
		}
		add_quad(&mesh, { 0.0, 0.0, 0.0 }, { 5.0, 0.0, 0.0 }, { 0.0, 1.5, 0.0 }, { 0.0, 0.0, 1.0 }); // z = 0
		add_quad(&mesh, { 5.0, 0.0, 0.0 }, { 0.0, 0.0, 4.0 }, { 0.0, 1.5, 0.0 }, { -1.0, 0.0, 0.0 }); // x = 5
		add_quad(&mesh, { 0.0, 0.0, 0.0 }, { 0.0, 0.0, 3.2 }, { 0.0, 1.5, 0.0 }, { 1.0, 0.0, 0.0 }); // x = 0, to the sofa
		if (p_back_wall_seen) {
			add_quad(&mesh, { 0.0, 0.9, 4.0 }, { 5.0, 0.0, 0.0 }, { 0.0, 0.6, 0.0 }, { 0.0, 0.0, -1.0 }); // z = 4, above the sofa
		}
		return estimate_from(mesh, truth, { { 2.5, 1.45, 1.5 } });
	};
	const Estimated seen = sweep(true);
	CAPTURE(seen.estimate.message);
	REQUIRE(seen.comparison.corners == 4); // partial only for the ceiling, not in this model
	CHECK(seen.estimate.message.find("the ceiling was not in the dense model") != std::string::npos);
	CHECK(seen.comparison.corner_error_max_m <= CORNER_TOLERANCE_M);
	// The wall x = 0 was seen over 3.2 m of its 4.
	const std::vector<double> &confidence = seen.estimate.edge_confidence;
	CHECK(*std::min_element(confidence.begin(), confidence.end()) == doctest::Approx(0.8).epsilon(0.02));
	// Without the wall behind the sofa nothing says the room goes on: it ends where the floor did,
	// that edge marked unseen.
	const Estimated unseen = sweep(false);
	CAPTURE(unseen.estimate.message);
	REQUIRE(unseen.estimate.state == RoomEstimateState::Partial);
	double depth_m = 0.0;
	for (const Vec2 &p : unseen.estimate.floorplan.points) {
		depth_m = std::max(depth_m, p.y);
	}
	double width_m = 0.0;
	for (const Vec2 &p : unseen.estimate.floorplan.points) {
		width_m = std::max(width_m, p.x);
	}
	// The estimated world's axes may be either way round; the short side is the depth seen.
	CHECK(std::min(depth_m, width_m) == doctest::Approx(3.2).epsilon(0.01));
	CHECK(*std::min_element(unseen.estimate.edge_confidence.begin(), unseen.estimate.edge_confidence.end()) == 0.0);
}

TEST_CASE("room estimation: a step of a few centimetres between two pieces of one wall is merged") {
	// An 8 x 4.5 m room whose wall z = 0 was placed at z = 0.013 over 7.44 m (the dense model) and
	// at z = 0 over the last 0.57 m (the fisheye), and whose wall z = 4.5 the same, 2.2 cm apart.
	std::vector<Vec2> points = { { 0.0, 0.013 }, { 7.442, 0.013 }, { 7.442, 0.0 }, { 8.0, 0.0 }, { 8.0, 4.49 }, { 7.442, 4.49 }, { 7.442, 4.512 }, { 0.0, 4.512 } };
	std::vector<double> confidence = { 0.95, 0.0, 0.5, 0.3, 0.5, 0.0, 1.0, 0.9 };
	merge_floorplan_steps(&points, &confidence);
	REQUIRE(points.size() == 4);
	REQUIRE(confidence.size() == 4);
	// The longer piece keeps its line; the edge's confidence is the pieces' length-weighted mean.
	const std::vector<Vec2> expected = { { 0.0, 0.013 }, { 8.0, 0.013 }, { 8.0, 4.512 }, { 0.0, 4.512 } };
	for (size_t i = 0; i < 4; i++) {
		CAPTURE(i);
		CHECK(points[i].x == doctest::Approx(expected[i].x));
		CHECK(points[i].y == doctest::Approx(expected[i].y));
	}
	CHECK(confidence[0] == doctest::Approx((0.95 * 7.442 + 0.5 * 0.558) / 8.0));
	CHECK(confidence[1] == doctest::Approx(0.3));
	CHECK(confidence[2] == doctest::Approx((0.5 * 0.558 + 1.0 * 7.442) / 8.0));
	CHECK(confidence[3] == doctest::Approx(0.9));
	// A real step (a partition's 12 cm end) and an L's corner stay.
	std::vector<Vec2> l_shape = { { 0.0, 0.0 }, { 6.0, 0.0 }, { 6.0, 3.0 }, { 3.0, 3.0 }, { 3.0, 5.0 }, { 0.0, 5.0 } };
	std::vector<double> l_confidence(6, 1.0);
	merge_floorplan_steps(&l_shape, &l_confidence);
	CHECK(l_shape.size() == 6);
	std::vector<Vec2> partition = figure4_two_rooms().points;
	std::vector<double> p_confidence(partition.size(), 1.0);
	merge_floorplan_steps(&partition, &p_confidence);
	CHECK(partition.size() == figure4_two_rooms().points.size());
}

TEST_CASE("room comparison: a turned and shifted room is its shape once fitted; a wall out of place stays an error") {
	const Floorplan truth = figure4_two_rooms();
	// The same room seen from a frame turned 0.5 degrees and shifted 4 cm: through the frames its
	// far corners miss by up to 8 m x 0.5 degrees + 4 cm; fitted, by nothing.
	Pose turned;
	turned.rotation = glm::angleAxis(glm::radians(0.5), glm::dvec3(0.0, 1.0, 0.0));
	turned.translation = glm::dvec3(0.03, 0.0, -0.025);
	const RoomComparison same = compare_rooms(truth, turned, truth, Pose());
	CHECK(same.corner_error_max_m >= 0.06);
	CHECK(same.corner_error_fitted_m <= 1e-6);
	// The right room's end wall 0.66 m short: no turn or shift hides it (at least half of it stays).
	Floorplan short_room = truth;
	for (Vec2 &p : short_room.points) {
		p.x = p.x > 7.9 ? 7.34 : p.x;
	}
	const RoomComparison shorter = compare_rooms(short_room, Pose(), truth, Pose());
	CHECK(shorter.corner_error_max_m == doctest::Approx(0.66).epsilon(1e-9));
	CHECK(shorter.corner_error_fitted_m >= 0.33);
}

TEST_CASE("room from a sweep: with no room file the world starts upright, the fisheye's axis up and the view down -Z") {
	auto check_upright = [](bool p_has_fisheye, const Pose &p_rgb_from_fisheye) {
		const Pose pose = upright_first_rgb_pose(p_has_fisheye, p_rgb_from_fisheye);
		const glm::dmat3 world_from_rgb = glm::mat3_cast(pose.rotation);
		const glm::dvec3 hint = p_has_fisheye ? p_rgb_from_fisheye.rotation * glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(0.0, -1.0, 0.0);
		const glm::dvec3 up = world_from_rgb * hint, view = world_from_rgb * glm::dvec3(0.0, 0.0, 1.0);
		CHECK(glm::length(up - glm::dvec3(0.0, 1.0, 0.0)) < 1e-9);
		CHECK(std::abs(view.x) < 1e-9); // levelled, the view is -Z
		CHECK(view.z < 0.0);
		CHECK(glm::length(pose.translation) == 0.0);
		CHECK(std::abs(glm::determinant(world_from_rgb) - 1.0) < 1e-9);
		return world_from_rgb;
	};
	// A camera without a fisheye, held level: its y (down) is -Y, its view -Z, its x +X.
	const glm::dmat3 level = check_upright(false, Pose());
	CHECK(glm::length(level * glm::dvec3(1.0, 0.0, 0.0) - glm::dvec3(1.0, 0.0, 0.0)) < 1e-9);
	CHECK(glm::length(level * glm::dvec3(0.0, 1.0, 0.0) - glm::dvec3(0.0, -1.0, 0.0)) < 1e-9);
	// The synthetic rig's upward fisheye, and one tilted 12 degrees forward and 5 sideways.
	check_upright(true, test_rig().rgb_from_fisheye);
	Pose tilted = test_rig().rgb_from_fisheye;
	tilted.rotation = glm::angleAxis(glm::radians(12.0), glm::dvec3(1.0, 0.0, 0.0)) * glm::angleAxis(glm::radians(5.0), glm::dvec3(0.0, 0.0, 1.0)) * tilted.rotation;
	check_upright(true, tilted);
}

TEST_CASE("room estimation: walls at other than right angles keep their angles") {
	Floorplan truth;
	truth.points = { { 0.0, 0.0 }, { 5.0, 0.0 }, { 5.0, 3.0 }, { 3.0, 4.5 }, { 0.0, 4.5 } }; // one wall at 36.9 degrees
	truth.ceiling_height_m = 2.5;
	RoomSurface seen;
	seen.ceiling = true;
	const Estimated result = estimate_from(room_mesh_of(truth, seen), truth, { { 2.0, 1.45, 2.0 } });
	CAPTURE(result.estimate.message);
	REQUIRE(result.estimate.state == RoomEstimateState::Complete);
	CHECK_FALSE(result.estimate.manhattan);
	CHECK(result.comparison.corners == 5);
	CHECK(result.comparison.corner_error_max_m <= CORNER_TOLERANCE_M);
}

TEST_CASE("room estimation: a sweep that saw one wall, or no floor, gives a clear state and no room") {
	const Floorplan truth = living_room();
	RoomSurface one_wall;
	one_wall.walls = { 0 };
	const Estimated wall = estimate_from(room_mesh_of(truth, one_wall), truth, { { 2.5, 1.45, 2.0 } });
	CHECK(wall.estimate.state == RoomEstimateState::TooFewWalls);
	CHECK(wall.estimate.message.find("1 wall seen") != std::string::npos);
	CHECK(wall.estimate.floorplan.points.empty());

	RoomSurface two_walls; // at a right angle: still no closed room
	two_walls.walls = { 0, 1 };
	const Estimated corner = estimate_from(room_mesh_of(truth, two_walls), truth, { { 2.5, 1.45, 2.0 } });
	CHECK(corner.estimate.state == RoomEstimateState::TooFewWalls);
	CHECK(corner.estimate.floorplan.points.empty());

	RoomSurface walls_only;
	walls_only.floor = false;
	const Estimated no_floor = estimate_from(room_mesh_of(truth, walls_only), truth, { { 2.5, 1.45, 2.0 } });
	CHECK(no_floor.estimate.state == RoomEstimateState::NoFloor);
	CHECK(no_floor.estimate.message.find("floor") != std::string::npos);

	const RoomEstimate nothing = estimate_room({}, glm::dvec3(0.0, 1.0, 0.0), {});
	CHECK(nothing.state == RoomEstimateState::NoSurface);
}

TEST_CASE("room estimation: a given floorplan is registered to the reconstructed walls; another room fits poorly") {
	const Floorplan truth = l_shaped_room();
	const Estimated result = estimate_from(room_mesh_of(truth, RoomSurface()), truth, { { 1.5, 1.45, 2.5 } });
	REQUIRE(result.estimate.floorplan.points.size() == 6);
	// The true floorplan, typed in its own frame, placed on the walls: its corners land on the
	// estimated ones (within 2 cm and 0.5 degrees, the figure; here the surfaces are exact).
	const FloorplanRegistration placed = register_floorplan(truth, result.world_samples);
	CAPTURE(placed.message);
	REQUIRE(placed.ok);
	CHECK_FALSE(placed.poor);
	CHECK(placed.residual_rms_m <= 0.005);
	Floorplan moved = truth;
	for (Vec2 &p : moved.points) {
		const glm::dvec3 q = transform_point(placed.world_from_given, glm::dvec3(p.x, 0.0, p.y));
		p = { q.x, q.z };
	}
	const RoomComparison landed = compare_rooms(moved, Pose(), result.estimate.floorplan, Pose());
	CHECK(landed.corner_error_max_m <= 0.02);
	// The L is not symmetric, so its yaw is unique: the estimated world's axes run along its walls.
	CHECK(std::abs(std::remainder(placed.yaw_deg, 90.0)) <= 0.5);

	Floorplan other;
	other.points = { { 0.0, 0.0 }, { 7.0, 0.0 }, { 7.0, 2.0 }, { 0.0, 2.0 } };
	other.ceiling_height_m = 2.4;
	const FloorplanRegistration wrong = register_floorplan(other, result.world_samples);
	CAPTURE(wrong.message);
	CHECK((!wrong.ok || wrong.poor));
}

TEST_CASE("room estimation: the fisheye finds the ceiling over textured walls, and a wall the RGB-D camera never saw") {
	// The living room, rendered: its walls carry stripes, bricks and checks (horizontal edges at
	// many heights), its ceiling tiles; 12 upward fisheye views along the hand-held orbit.
	synth::SceneOptions options;
	options.duration_s = 10.0;
	const synth::SceneResult made = synth::make_scene("living_room", options);
	REQUIRE(made.ok);
	synth::SynthRenderer renderer(made.scene);
	REQUIRE(renderer.ok());
	const Rig rig = small_test_rig(32, 24, 512, 512);
	const synth::HandheldTrajectory trajectory = synth::make_handheld_trajectory(made.scene, 1);
	std::vector<FisheyeView> views;
	for (int i = 0; i < 12; i++) {
		const double t = 0.2 + 0.8 * i; // before the ceiling light switches on at 5 s too
		const Pose world_from_fisheye = compose(trajectory.world_from_rgb(t), rig.rgb_from_fisheye);
		views.push_back({ synth::render_fisheye(renderer, rig.fisheye, world_from_fisheye, t, synth::FisheyeOptions()).image, world_from_fisheye });
	}
	Floorplan plan = living_room();
	const double true_ceiling_m = plan.ceiling_height_m;
	plan.ceiling_height_m = 0.0;
	// Tolerance: at 512 px the fisheye sees about 0.4 degrees a pixel; the walls' top edges lie
	// 1.5 to 3.5 m from the orbit, 1 m above it, so a pixel spans 1.5 to 4 cm of height there:
	// the 3 cm is under a pixel on the nearer walls.
	const CeilingSearch ceiling = ceiling_from_fisheye(views, rig.fisheye, plan, 1.8, 4.0);
	CAPTURE(ceiling.message);
	REQUIRE(ceiling.ok);
	CHECK(std::abs(ceiling.height_m - true_ceiling_m) <= 0.03);

	// Wall 1 (x = 5) as a sweep that never looked there leaves it: 60 cm short, confidence 0.
	Floorplan partial = living_room();
	partial.ceiling_height_m = ceiling.height_m;
	partial.points[1].x = 4.4;
	partial.points[2].x = 4.4;
	std::vector<double> confidence = { 1.0, 0.0, 1.0, 1.0 };
	const std::vector<std::string> lines = complete_walls_from_fisheye(views, rig.fisheye, &partial, &confidence);
	CAPTURE(lines.size() == 1 ? lines[0] : std::string());
	CHECK(confidence[1] == FISHEYE_WALL_CONFIDENCE);
	CHECK(std::abs(partial.points[1].x - 5.0) <= 0.05);
	CHECK(std::abs(partial.points[2].x - 5.0) <= 0.05);
	CHECK(partial.points[1].y == 0.0);

	// Wall 1 where it stands, but marked unseen: the search starts on the true wall, and the
	// positions beyond it are behind it (the views see its stripes there). The wall is confirmed
	// where it stands, not moved behind itself.
	Floorplan whole = living_room();
	whole.ceiling_height_m = ceiling.height_m;
	std::vector<double> unseen = { 1.0, 0.0, 1.0, 1.0 };
	const std::vector<std::string> beyond = complete_walls_from_fisheye(views, rig.fisheye, &whole, &unseen);
	CAPTURE(beyond.size() == 1 ? beyond[0] : std::string());
	CHECK(std::abs(whole.points[1].x - 5.0) <= 0.05);
	CHECK(std::abs(whole.points[2].x - 5.0) <= 0.05);

	// Views with no edges at all (a uniform sky): no ceiling, said so.
	std::vector<FisheyeView> blank = views;
	for (FisheyeView &view : blank) {
		view.image = cv::Mat(view.image.size(), view.image.type(), cv::Scalar::all(128));
	}
	const CeilingSearch none = ceiling_from_fisheye(blank, rig.fisheye, plan, 1.8, 4.0);
	CHECK_FALSE(none.ok);
	CHECK(none.message.find("no clear wall-ceiling edge") != std::string::npos);
}
