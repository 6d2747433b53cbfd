// Rendering the coarse model into a cubemap (paper §4.7): the exact ray / prism intersection
// and the atlas lookup, checked with an atlas whose texels hold their own world position.

#include <io/opencv.h>

#include "envmap/coarse_render.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>

using namespace roomprobe;

namespace {

RoomMesh build(const Floorplan &p_floorplan) {
	const RoomMeshResult result = build_room_mesh(p_floorplan);
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.mesh;
}

// A 4 m x 3 m box, 2.5 m high.
Floorplan box_room() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 3.0 }, { 0.0, 3.0 } };
	floorplan.ceiling_height_m = 2.5;
	return floorplan;
}

// An L: the box above without its x > 2, z > 1.5 corner.
Floorplan l_room() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 1.5 }, { 2.0, 1.5 }, { 2.0, 3.0 }, { 0.0, 3.0 } };
	floorplan.ceiling_height_m = 2.5;
	return floorplan;
}

// The atlas colour of every surface texel is its centre's world position; 0 elsewhere.
cv::Mat position_atlas(const RoomMesh &p_mesh) {
	cv::Mat atlas(p_mesh.atlas_height, p_mesh.atlas_width, CV_32FC3, cv::Scalar::all(0.0));
	for (int y = 0; y < atlas.rows; y++) {
		for (int x = 0; x < atlas.cols; x++) {
			Vec3 point;
			if (texel_to_world(p_mesh, x, y, &point, nullptr)) {
				atlas.at<cv::Vec3f>(y, x) = cv::Vec3f(float(point.x), float(point.y), float(point.z));
			}
		}
	}
	return atlas;
}

// The distance from p_origin along unit p_direction to the walls of an axis-aligned box.
double box_distance(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, const glm::dvec3 &p_max) {
	double best = std::numeric_limits<double>::infinity();
	for (int axis = 0; axis < 3; axis++) {
		if (p_direction[axis] > 0.0) {
			best = std::min(best, (p_max[axis] - p_origin[axis]) / p_direction[axis]);
		} else if (p_direction[axis] < 0.0) {
			best = std::min(best, -p_origin[axis] / p_direction[axis]);
		}
	}
	return best;
}

bool inside_floorplan(const Floorplan &p_floorplan, double p_x, double p_z) {
	bool inside = false;
	const std::vector<Vec2> &points = p_floorplan.points;
	for (size_t i = 0, j = points.size() - 1; i < points.size(); j = i++) {
		if ((points[i].y > p_z) != (points[j].y > p_z) &&
				p_x < points[i].x + (p_z - points[i].y) * (points[j].x - points[i].x) / (points[j].y - points[i].y)) {
			inside = !inside;
		}
	}
	return inside;
}

} // namespace

TEST_CASE("intersect_room hits a box room's planes at the analytic distance") {
	const RoomMesh mesh = build(box_room());
	const glm::dvec3 origin(1.3, 1.1, 1.7);
	const int n = 32;
	for (int face = 0; face < 6; face++) {
		for (int v = 0; v < n; v++) {
			for (int u = 0; u < n; u++) {
				const glm::dvec3 d = cubemap_direction(face, u, v, n);
				RoomRayHit hit;
				REQUIRE(intersect_room(mesh, origin, d, &hit));
				CHECK(hit.distance == doctest::Approx(box_distance(origin, d, glm::dvec3(4.0, 2.5, 3.0))).epsilon(1e-12));
				// The atlas position maps back onto the hit point through the chart's axes.
				const Chart &chart = mesh.charts[size_t(hit.chart)];
				const glm::dvec3 back = glm::dvec3(chart.origin_m.x, chart.origin_m.y, chart.origin_m.z) +
						glm::dvec3(chart.u_axis_m.x, chart.u_axis_m.y, chart.u_axis_m.z) * (hit.atlas.x - chart.x) +
						glm::dvec3(chart.v_axis_m.x, chart.v_axis_m.y, chart.v_axis_m.z) * (hit.atlas.y - chart.y);
				CHECK(glm::length(back - hit.point) < 1e-9);
				CHECK(hit.atlas.x >= chart.x - 1e-9);
				CHECK(hit.atlas.x <= chart.x + chart.used_w_texels + 1e-9);
				CHECK(hit.atlas.y >= chart.y - 1e-9);
				CHECK(hit.atlas.y <= chart.y + chart.used_h_texels + 1e-9);
			}
		}
	}
}

TEST_CASE("intersect_room in an L-shaped room stops at the nearest surface, seen through the room") {
	const Floorplan floorplan = l_room();
	const RoomMesh mesh = build(floorplan);
	const glm::dvec3 origin(1.0, 1.2, 0.8);
	const int n = 24;
	int walls_hit = 0;
	for (int face = 0; face < 6; face++) {
		for (int v = 0; v < n; v++) {
			for (int u = 0; u < n; u++) {
				const glm::dvec3 d = cubemap_direction(face, u, v, n);
				RoomRayHit hit;
				REQUIRE(intersect_room(mesh, origin, d, &hit));
				CHECK(hit.point.y >= -1e-9);
				CHECK(hit.point.y <= 2.5 + 1e-9);
				// Every point before the hit is inside the room.
				for (int k = 1; k < 20; k++) {
					const glm::dvec3 p = origin + d * (hit.distance * k / 20.0);
					CHECK(inside_floorplan(floorplan, p.x, p.z));
				}
				// And the hit is on the boundary: a little further is outside (or through the floor / ceiling).
				const glm::dvec3 beyond = origin + d * (hit.distance + 1e-6);
				CHECK((beyond.y < 0.0 || beyond.y > 2.5 || !inside_floorplan(floorplan, beyond.x, beyond.z)));
				walls_hit += hit.chart < int(floorplan.points.size()) ? 1 : 0;
			}
		}
	}
	CHECK(walls_hit > 0);
}

TEST_CASE("a coarse render of a position atlas shows, at each pixel, the point along its ray") {
	for (const Floorplan &floorplan : { box_room(), l_room() }) {
		const RoomMesh mesh = build(floorplan);
		const cv::Mat atlas = position_atlas(mesh);
		const CoarseCubemapRenderer renderer(mesh);
		const glm::dvec3 origin(1.3, 1.1, 0.9);
		const int n = 48;
		CoarseTexture texture;
		texture.color = atlas;
		const Cubemap cubemap = renderer.render(texture, origin, n);
		REQUIRE(is_valid_cubemap(cubemap));
		REQUIRE(cubemap.size == n);
		double worst = 0.0;
		for (int face = 0; face < 6; face++) {
			for (int v = 0; v < n; v++) {
				for (int u = 0; u < n; u++) {
					const glm::dvec3 d = cubemap_direction(face, u, v, n);
					RoomRayHit hit;
					REQUIRE(intersect_room(mesh, origin, d, &hit));
					const cv::Vec3f c = cubemap.faces[size_t(face)].at<cv::Vec3f>(v, u);
					const glm::dvec3 decoded(c[0], c[1], c[2]);
					if (floorplan.points.size() == 4) {
						const double expected = box_distance(origin, d, glm::dvec3(4.0, 2.5, 3.0));
						worst = std::max(worst, glm::length(decoded - (origin + d * expected)));
					} else {
						worst = std::max(worst, glm::length(decoded - hit.point));
					}
				}
			}
		}
		// Bilinear interpolation of a position atlas is exact inside a chart; the clamp to the
		// last texel centre costs at most half a texel along each chart axis.
		CHECK(worst <= mesh.texel_size_m * 0.75);
	}
}

TEST_CASE("a coarse render samples the atlas bilinearly without bleeding across charts") {
	const RoomMesh mesh = build(box_room());
	cv::Mat atlas(mesh.atlas_height, mesh.atlas_width, CV_32FC3, cv::Scalar::all(100.0)); // padding: a loud value
	for (int y = 0; y < atlas.rows; y++) {
		for (int x = 0; x < atlas.cols; x++) {
			const int chart = find_chart_at_texel(mesh, x, y);
			if (chart >= 0 && texel_to_world(mesh, x, y, nullptr, nullptr)) {
				atlas.at<cv::Vec3f>(y, x) = cv::Vec3f(float(chart), 1.0f, 0.5f);
			}
		}
	}
	const CoarseCubemapRenderer renderer(mesh);
	const glm::dvec3 origin(2.0, 1.25, 1.5);
	const int n = 32;
	const Cubemap cubemap = renderer.render(atlas, origin, n);
	REQUIRE(is_valid_cubemap(cubemap));
	for (int face = 0; face < 6; face++) {
		for (int v = 0; v < n; v++) {
			for (int u = 0; u < n; u++) {
				RoomRayHit hit;
				REQUIRE(intersect_room(mesh, origin, cubemap_direction(face, u, v, n), &hit));
				const cv::Vec3f c = cubemap.faces[size_t(face)].at<cv::Vec3f>(v, u);
				CHECK(c[0] == float(hit.chart));
				CHECK(c[1] == 1.0f);
			}
		}
	}
	// An atlas of the wrong size gives no cubemap.
	CHECK(!is_valid_cubemap(renderer.render(cv::Mat(4, 4, CV_32FC3), origin, n)));
}

TEST_CASE("a coarse render through kept rays equals the first render, follows the atlas, and is rebuilt after eviction") {
	const RoomMesh mesh = build(l_room());
	const cv::Mat atlas = position_atlas(mesh);
	const CoarseCubemapRenderer renderer(mesh);
	const glm::dvec3 origin(1.3, 1.1, 0.9);
	const int n = 32;
	const Cubemap first = renderer.render(atlas, origin, n);
	REQUIRE(is_valid_cubemap(first));
	const auto max_difference = [&](const Cubemap &p_a, const Cubemap &p_b, double p_scale_b) {
		double worst = 0.0;
		for (int f = 0; f < 6; f++) {
			worst = std::max(worst, cv::norm(p_a.faces[size_t(f)] * p_scale_b, p_b.faces[size_t(f)], cv::NORM_INF));
		}
		return worst;
	};
	// The same position again (kept rays), then more positions than are kept, then again.
	CHECK(max_difference(first, renderer.render(atlas, origin, n), 1.0) == 0.0);
	for (int i = 0; i < CoarseCubemapRenderer::MAX_CACHED_LOOKUPS + 1; i++) {
		const Cubemap other = renderer.render(atlas, origin + glm::dvec3(0.1 * (i + 1), 0.0, 0.0), n);
		CHECK(max_difference(first, other, 1.0) > 0.01); // another position sees other points
	}
	CHECK(max_difference(first, renderer.render(atlas, origin, n), 1.0) == 0.0);
	// The kept rays hold no colours: a new atlas shows at once.
	const cv::Mat doubled = atlas * 2.0;
	CHECK(max_difference(first, renderer.render(doubled, origin, n), 2.0) < 1e-5);
	// Another size at the same position is its own set of rays.
	CHECK(renderer.render(atlas, origin, n / 2).size == n / 2);
}

TEST_CASE("a one-channel render of an atlas is that channel of the colour render") {
	const RoomMesh mesh = build(l_room());
	const cv::Mat atlas = position_atlas(mesh);
	const CoarseCubemapRenderer renderer(mesh);
	const glm::dvec3 origin(1.3, 1.1, 0.9);
	const int n = 32;
	std::vector<cv::Mat> channels;
	cv::split(atlas, channels);
	const Cubemap colour = renderer.render(atlas, origin, n);
	for (int c = 0; c < 3; c++) {
		const std::array<cv::Mat, 6> faces = renderer.render_channel(channels[size_t(c)], origin, n);
		for (int f = 0; f < 6; f++) {
			REQUIRE(faces[size_t(f)].type() == CV_32FC1);
			cv::Mat expected;
			cv::extractChannel(colour.faces[size_t(f)], expected, c);
			CHECK(cv::norm(faces[size_t(f)], expected, cv::NORM_INF) == 0.0);
		}
	}
	// A colour atlas, or one of another size, is refused: empty faces.
	CHECK(renderer.render_channel(atlas, origin, n)[0].empty());
	CHECK(renderer.render_channel(cv::Mat(4, 4, CV_32FC1, cv::Scalar(0.0)), origin, n)[0].empty());
}
