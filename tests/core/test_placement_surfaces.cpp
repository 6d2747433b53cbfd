// placement/surface_placement.h: rays meet the dense mesh or the room prism, the nearer wins.

#include "placement/surface_placement.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

using namespace roomprobe;

namespace {

RoomMesh box_room() {
	Floorplan plan;
	plan.points = { Vec2(0.0, 0.0), Vec2(4.0, 0.0), Vec2(4.0, 3.0), Vec2(0.0, 3.0) };
	plan.ceiling_height_m = 2.5;
	RoomMeshResult built = build_room_mesh(plan, RoomMeshOptions());
	REQUIRE(built.ok);
	return built.mesh;
}

// A 1 m x 0.6 m table top at y = 0.75 around (2, 1.5), as the dense model would mesh it.
TriangleMesh table_top() {
	TriangleMesh mesh;
	mesh.vertices = { { 1.5f, 0.75f, 1.2f }, { 2.5f, 0.75f, 1.2f }, { 2.5f, 0.75f, 1.8f }, { 1.5f, 0.75f, 1.8f } };
	mesh.normals.assign(4, glm::vec3(0.0f, 1.0f, 0.0f));
	mesh.colors.assign(4, glm::u8vec3(200, 180, 150));
	mesh.indices = { 0, 2, 1, 0, 3, 2 };
	return mesh;
}

} // namespace

TEST_CASE("placement: the table top, the floor beside it, the ceiling and a wall") {
	SurfacePlacer placer;
	REQUIRE(placer.set_coarse(box_room()) == "");
	REQUIRE(placer.set_dense(table_top()) == "");

	const PlacementHit on_table = placer.cast({ 2.0, 1.6, 1.5 }, { 0.0, -2.0, 0.0 });
	CHECK(on_table.surface == PlacementSurface::Dense);
	CHECK(on_table.point.y == doctest::Approx(0.75).epsilon(1e-6));
	CHECK(on_table.distance_m == doctest::Approx(0.85).epsilon(1e-6));
	CHECK(on_table.normal.y == doctest::Approx(1.0));

	const PlacementHit on_floor = placer.cast({ 3.5, 1.6, 0.5 }, { 0.0, -1.0, 0.0 });
	CHECK(on_floor.surface == PlacementSurface::Coarse);
	CHECK(on_floor.point.y == doctest::Approx(0.0).epsilon(1e-6));
	CHECK(on_floor.normal.y == doctest::Approx(1.0));

	const PlacementHit ceiling = placer.cast({ 2.0, 1.6, 1.5 }, { 0.0, 1.0, 0.0 });
	CHECK(ceiling.surface == PlacementSurface::Coarse);
	CHECK(ceiling.point.y == doctest::Approx(2.5).epsilon(1e-6));
	CHECK(ceiling.normal.y == doctest::Approx(-1.0)); // facing the ray's origin

	// Towards the x = 4 wall at a slant: the hit lies on the wall, 2 m away in x.
	const PlacementHit wall = placer.cast({ 2.0, 1.6, 1.5 }, { 1.0, 0.0, 0.5 });
	CHECK(wall.surface == PlacementSurface::Coarse);
	CHECK(wall.point.x == doctest::Approx(4.0).epsilon(1e-6));
	CHECK(wall.point.z == doctest::Approx(2.5).epsilon(1e-6));
	CHECK(wall.normal.x == doctest::Approx(-1.0));

	// Nothing within reach, and a zero direction.
	CHECK(placer.cast({ 2.0, 1.6, 1.5 }, { 0.0, -1.0, 0.0 }, 0.5).surface == PlacementSurface::None);
	CHECK(placer.cast({ 2.0, 1.6, 1.5 }, { 0.0, 0.0, 0.0 }).surface == PlacementSurface::None);

	// Without the dense model the same ray reaches the floor.
	placer.clear_dense();
	CHECK(placer.cast({ 2.0, 1.6, 1.5 }, { 0.0, -1.0, 0.0 }).surface == PlacementSurface::Coarse);
}
