// Occlusion in the coarse model (paper §4.4): the visibility polygon's mask against Embree rays, on the
// paper's Figure-4 two rooms and the convex living room.

#include "io/opencv.h"
#include "coarse/occlusion.h"
#include "coarse/texture_update.h"
#include "room/reference_rooms.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

using namespace roomprobe;

namespace {

RoomMesh build(const Floorplan &p_floorplan) {
	const RoomMeshResult result = build_room_mesh(p_floorplan);
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.mesh;
}

glm::dvec3 to_glm(const Vec3 &p_v) {
	return glm::dvec3(p_v.x, p_v.y, p_v.z);
}

// The texel (x, y) of the surface point p_world on a chart of p_kind, or (-1, -1).
cv::Point texel_at(const RoomMesh &p_mesh, SurfaceKind p_kind, const glm::dvec3 &p_world) {
	for (const Chart &chart : p_mesh.charts) {
		if (chart.kind != p_kind) {
			continue;
		}
		const glm::dvec3 d = p_world - to_glm(chart.origin_m);
		if (std::abs(glm::dot(d, to_glm(chart.normal))) > 1e-6) {
			continue;
		}
		const glm::dvec3 u = to_glm(chart.u_axis_m), v = to_glm(chart.v_axis_m);
		const double s = glm::dot(d, u) / glm::dot(u, u), t = glm::dot(d, v) / glm::dot(v, v);
		if (s >= 0.0 && t >= 0.0 && s <= chart.used_w_texels && t <= chart.used_h_texels) {
			return cv::Point(chart.x + int(s), chart.y + int(t));
		}
	}
	return cv::Point(-1, -1);
}

bool visible(const cv::Mat &p_mask, const cv::Point &p_texel) {
	REQUIRE(p_texel.x >= 0);
	return p_mask.at<uint8_t>(p_texel) == 255;
}

double seconds_since(std::chrono::steady_clock::time_point p_start) {
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - p_start).count();
}

} // namespace

TEST_CASE("coarse occlusion: convexity of the reference floorplans") {
	CHECK(floorplan_is_convex(living_room()));
	CHECK_FALSE(floorplan_is_convex(figure4_two_rooms()));
	CHECK_FALSE(floorplan_is_convex(l_shaped_room()));
	Floorplan reversed = living_room();
	std::reverse(reversed.points.begin(), reversed.points.end());
	CHECK(floorplan_is_convex(reversed));
}

TEST_CASE("coarse occlusion: visibility polygons in the two rooms") {
	const Floorplan plan = figure4_two_rooms();
	// From the left room's middle, the right room's x = 8 wall near z = 0.5 is behind the partition.
	const VisibilityPolygon left = visibility_polygon(plan, glm::dvec2(2.0, 1.0));
	REQUIRE_MESSAGE(left.ok, left.error);
	CHECK(left.points.size() >= 4);
	CHECK(point_in_polygon(left.points, glm::dvec2(0.1, 4.4)));
	CHECK(point_in_polygon(left.points, glm::dvec2(3.9, 0.1)));
	CHECK(point_in_polygon(left.points, glm::dvec2(5.0, 4.4)));
	CHECK_FALSE(point_in_polygon(left.points, glm::dvec2(7.9, 0.5)));
	CHECK_FALSE(point_in_polygon(left.points, glm::dvec2(6.0, 0.1)));
	CHECK_FALSE(point_in_polygon(left.points, glm::dvec2(7.0, 4.4)));
	// Its area is less than the floorplan's 35.64 m^2.
	double area2 = 0.0;
	for (size_t i = 0; i < left.points.size(); ++i) {
		const glm::dvec2 &a = left.points[i], &b = left.points[(i + 1) % left.points.size()];
		area2 += a.x * b.y - b.x * a.y;
	}
	CHECK(area2 > 0.0);
	CHECK(0.5 * area2 < 35.64 - 5.0);
	// From the doorway (below the partition's tip) everything is visible.
	const VisibilityPolygon door = visibility_polygon(plan, glm::dvec2(4.0, 3.75));
	REQUIRE(door.ok);
	CHECK(point_in_polygon(door.points, glm::dvec2(0.1, 0.1)));
	CHECK(point_in_polygon(door.points, glm::dvec2(7.9, 0.1)));
	// Outside the room, or inside the partition: no polygon.
	CHECK_FALSE(visibility_polygon(plan, glm::dvec2(9.0, 1.0)).ok);
	CHECK_FALSE(visibility_polygon(plan, glm::dvec2(4.0, 1.0)).ok);
}

TEST_CASE("coarse occlusion: a convex room is all visible") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const cv::Mat mask = occlusion_mask(mesh, geometry, glm::dvec3(1.0, 1.4, 3.0));
	REQUIRE(mask.size() == cv::Size(mesh.atlas_width, mesh.atlas_height));
	CHECK(size_t(cv::countNonZero(mask)) == geometry.surface_texels);
	const cv::Mat rays = occlusion_mask_embree(mesh, geometry, glm::dvec3(1.0, 1.4, 3.0));
	CHECK(size_t(cv::countNonZero(rays)) == geometry.surface_texels);
}

TEST_CASE("coarse occlusion: the visibility polygon's mask agrees with Embree's rays in the two rooms, except at shadow boundaries") {
	const RoomMesh mesh = build(figure4_two_rooms());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const EmbreeOcclusion tracer(mesh);
	REQUIRE_MESSAGE(tracer.ok(), tracer.error());
	for (const glm::dvec3 &camera : { glm::dvec3(2.0, 1.45, 1.0), glm::dvec3(1.2, 1.6, 3.9), glm::dvec3(6.5, 1.3, 0.7) }) {
		CAPTURE(camera.x);
		CAPTURE(camera.z);
		auto start = std::chrono::steady_clock::now();
		const cv::Mat polygon = occlusion_mask(mesh, geometry, camera);
		const double polygon_s = seconds_since(start);
		start = std::chrono::steady_clock::now();
		const cv::Mat rays = tracer.mask(geometry, camera);
		const double rays_s = seconds_since(start);
		size_t total = 0, agree = 0, visible_texels = 0, unexplained = 0, off_surface_visible = 0;
		const int w = geometry.width, h = geometry.height;
		for (int y = 0; y < h; ++y) {
			for (int x = 0; x < w; ++x) {
				if (!geometry.on_surface(x, y)) {
					off_surface_visible += polygon.at<uint8_t>(y, x) != 0 || rays.at<uint8_t>(y, x) != 0;
					continue;
				}
				++total;
				const uint8_t c = polygon.at<uint8_t>(y, x);
				visible_texels += c == 255;
				if (c == rays.at<uint8_t>(y, x)) {
					++agree;
					continue;
				}
				// A disagreement must sit at a boundary of the polygon's mask (within 2 texels).
				bool boundary = false;
				for (int dy = -2; dy <= 2 && !boundary; ++dy) {
					for (int dx = -2; dx <= 2 && !boundary; ++dx) {
						const int xx = x + dx, yy = y + dy;
						boundary = xx >= 0 && yy >= 0 && xx < w && yy < h && geometry.on_surface(xx, yy) && polygon.at<uint8_t>(yy, xx) != c;
					}
				}
				unexplained += !boundary;
			}
		}
		const double agreement = double(agree) / double(total);
		MESSAGE("camera (" << camera.x << ", " << camera.z << "): " << total << " surface texels, " << visible_texels
						   << " visible (polygon), agreement " << 100.0 * agreement << " % (" << total - agree << " differ), polygon mask "
						   << 1000.0 * polygon_s << " ms, Embree mask " << 1000.0 * rays_s << " ms");
		CHECK(agreement >= 0.995);
		CHECK(unexplained == 0);
		CHECK(off_surface_visible == 0);
		CHECK(visible_texels < total); // something is hidden from every one of these viewpoints
	}
}

TEST_CASE("coarse occlusion: spot checks from the left room") {
	const RoomMesh mesh = build(figure4_two_rooms());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const glm::dvec3 camera(2.0, 1.45, 1.0);
	const cv::Mat polygon = occlusion_mask(mesh, geometry, camera);
	const cv::Mat rays = occlusion_mask_embree(mesh, geometry, camera);
	REQUIRE_FALSE(rays.empty());
	for (const cv::Mat &mask : { polygon, rays }) {
		// The left room's far walls (x = 0 and z = 4.5), its floor and ceiling.
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(0.0, 1.0, 2.0))));
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(1.0, 2.0, 4.5))));
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Floor, glm::dvec3(1.0, 0.0, 3.0))));
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Ceiling, glm::dvec3(3.0, 2.6, 0.5))));
		// The partition's face towards the left room; not its face towards the right room.
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(3.94, 1.0, 1.5))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(4.06, 1.0, 1.5))));
		// The right room's walls behind the partition: x = 8 and the z = 0 wall.
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(8.0, 1.0, 0.5))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(8.0, 1.0, 4.4))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(6.0, 2.0, 0.0))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Floor, glm::dvec3(6.0, 0.0, 1.0))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Ceiling, glm::dvec3(7.0, 2.6, 2.0))));
		// Through the opening: the z = 4.5 wall of the right room up to x ~ 5.6, not beyond.
		CHECK(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(5.0, 1.0, 4.5))));
		CHECK_FALSE(visible(mask, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(7.0, 1.0, 4.5))));
	}
}

TEST_CASE("coarse occlusion: extra occluders hide what is behind them, and a viewpoint outside sees nothing") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const glm::dvec3 camera(2.5, 1.4, 2.0);
	// A 1 m square screen in front of the x = 0 wall, facing the camera.
	const std::vector<glm::dvec3> screen = { { 1.0, 0.9, 1.5 }, { 1.0, 1.9, 1.5 }, { 1.0, 1.9, 2.5 }, { 1.0, 0.9, 1.5 }, { 1.0, 1.9, 2.5 },
		{ 1.0, 0.9, 2.5 } };
	const cv::Mat rays = occlusion_mask_embree(mesh, geometry, camera, screen);
	CHECK_FALSE(visible(rays, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(0.0, 1.4, 2.0))));
	CHECK(visible(rays, texel_at(mesh, SurfaceKind::Wall, glm::dvec3(0.0, 0.3, 0.5))));
	const cv::Mat outside = occlusion_mask(mesh, geometry, glm::dvec3(7.0, 1.4, 2.0), OcclusionOptions { 1e-3, false });
	CHECK(cv::countNonZero(outside) == 0);
}

TEST_CASE("coarse occlusion: the mask of the tiles a frame sees is the plain mask there, and 0 elsewhere") {
	const RoomMesh mesh = build(figure4_two_rooms());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	OmniParams lens; // a 190-degree fisheye looking along the world's +x
	lens.width = lens.height = 512;
	lens.xi = 1.0;
	lens.fx = lens.fy = 240.0;
	lens.cx = lens.cy = lens.circle_cx = lens.circle_cy = 255.5;
	lens.circle_radius = 250.0;
	Pose pose;
	pose.rotation = glm::quat_cast(glm::dmat3(glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0)));
	TexelProjection projection;
	cv::Mat mask;
	for (const glm::dvec3 &camera : { glm::dvec3(2.0, 1.45, 1.0), glm::dvec3(6.5, 1.3, 0.7) }) {
		CAPTURE(camera.x);
		pose.translation = camera;
		project_texels(geometry, lens, pose, &projection);
		occlusion_mask(mesh, geometry, camera, projection, &mask);
		const cv::Mat plain = occlusion_mask(mesh, geometry, camera);
		int seen = 0, unseen = 0, differing = 0;
		for (int y = 0; y < geometry.height; y++) {
			for (int x = 0; x < geometry.width; x++) {
				if (!geometry.on_surface(x, y)) {
					continue;
				}
				const bool in_seen_tile = projection.seen(geometry, x, y);
				(in_seen_tile ? seen : unseen)++;
				differing += mask.at<uint8_t>(y, x) != (in_seen_tile ? plain.at<uint8_t>(y, x) : 0) ? 1 : 0;
			}
		}
		CHECK(seen > 1000);
		CHECK(unseen > 1000);
		CHECK(differing == 0);
	}
}
