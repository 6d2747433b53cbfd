// Coarse room mesh (paper §4.1): closed prism, inward normals, uniform-texel atlas.

#include "room/floorplan.h"
#include "room/reference_rooms.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

using namespace roomprobe;

namespace {

struct V3 {
	double x, y, z;
};

V3 to_v3(const Vec3f &p_v) {
	return { p_v.x, p_v.y, p_v.z };
}

V3 to_v3(const Vec3 &p_v) {
	return { p_v.x, p_v.y, p_v.z };
}

V3 sub(const V3 &p_a, const V3 &p_b) {
	return { p_a.x - p_b.x, p_a.y - p_b.y, p_a.z - p_b.z };
}

V3 cross(const V3 &p_a, const V3 &p_b) {
	return { p_a.y * p_b.z - p_a.z * p_b.y, p_a.z * p_b.x - p_a.x * p_b.z, p_a.x * p_b.y - p_a.y * p_b.x };
}

double dot(const V3 &p_a, const V3 &p_b) {
	return p_a.x * p_b.x + p_a.y * p_b.y + p_a.z * p_b.z;
}

double length(const V3 &p_v) {
	return std::sqrt(dot(p_v, p_v));
}

// Even-odd test in the (x, z) plane; independent of the CGAL code under test.
bool inside_polygon(const std::vector<Vec2> &p_points, double p_x, double p_z) {
	bool inside = false;
	for (size_t i = 0, j = p_points.size() - 1; i < p_points.size(); j = i++) {
		const Vec2 &a = p_points[i];
		const Vec2 &b = p_points[j];
		if ((a.y > p_z) != (b.y > p_z) && p_x < (b.x - a.x) * (p_z - a.y) / (b.y - a.y) + a.x) {
			inside = !inside;
		}
	}
	return inside;
}

double distance_to_segment_2d(const Vec2 &p_a, const Vec2 &p_b, double p_x, double p_z) {
	const double dx = p_b.x - p_a.x;
	const double dz = p_b.y - p_a.y;
	const double t = std::clamp(((p_x - p_a.x) * dx + (p_z - p_a.y) * dz) / (dx * dx + dz * dz), 0.0, 1.0);
	return std::hypot(p_a.x + t * dx - p_x, p_a.y + t * dz - p_z);
}

double distance_to_boundary_2d(const std::vector<Vec2> &p_points, double p_x, double p_z) {
	double best = INFINITY;
	for (size_t i = 0; i < p_points.size(); ++i) {
		best = std::min(best, distance_to_segment_2d(p_points[i], p_points[(i + 1) % p_points.size()], p_x, p_z));
	}
	return best;
}

double polygon_area(const std::vector<Vec2> &p_points) {
	double twice = 0.0;
	for (size_t i = 0; i < p_points.size(); ++i) {
		const Vec2 &a = p_points[i];
		const Vec2 &b = p_points[(i + 1) % p_points.size()];
		twice += a.x * b.y - b.x * a.y;
	}
	return std::abs(0.5 * twice);
}

double polygon_perimeter(const std::vector<Vec2> &p_points) {
	double sum = 0.0;
	for (size_t i = 0; i < p_points.size(); ++i) {
		const Vec2 &a = p_points[i];
		const Vec2 &b = p_points[(i + 1) % p_points.size()];
		sum += std::hypot(b.x - a.x, b.y - a.y);
	}
	return sum;
}

size_t triangle_count(const RoomMesh &p_mesh) {
	return p_mesh.indices.size() / 3;
}

V3 corner(const RoomMesh &p_mesh, size_t p_triangle, int p_corner) {
	return to_v3(p_mesh.positions[p_mesh.indices[3 * p_triangle + p_corner]]);
}

// UV of a triangle corner in continuous atlas pixel units.
std::pair<double, double> corner_pixel(const RoomMesh &p_mesh, size_t p_triangle, int p_corner) {
	const Vec2f &uv = p_mesh.uvs[p_mesh.indices[3 * p_triangle + p_corner]];
	return { double(uv.x) * p_mesh.atlas_width, double(uv.y) * p_mesh.atlas_height };
}

void check_array_sizes(const RoomMesh &p_mesh, size_t p_corners) {
	CHECK(p_mesh.positions.size() == 6 * p_corners); // 4 per wall + floor + ceiling copies.
	CHECK(p_mesh.normals.size() == p_mesh.positions.size());
	CHECK(p_mesh.uvs.size() == p_mesh.positions.size());
	CHECK(p_mesh.vertex_charts.size() == p_mesh.positions.size());
	CHECK(p_mesh.indices.size() % 3 == 0);
	CHECK(triangle_count(p_mesh) == 4 * p_corners - 4); // 2 per wall + 2 * (n - 2).
	CHECK(p_mesh.triangle_charts.size() == triangle_count(p_mesh));
	CHECK(p_mesh.charts.size() == p_corners + 2);
	for (uint32_t index : p_mesh.indices) {
		CHECK(index < p_mesh.positions.size());
	}
	for (size_t i = 0; i < p_corners; ++i) {
		CHECK(p_mesh.charts[i].kind == SurfaceKind::Wall);
		CHECK(p_mesh.charts[i].wall_index == int(i));
	}
	CHECK(p_mesh.charts[p_corners].kind == SurfaceKind::Floor);
	CHECK(p_mesh.charts[p_corners].wall_index == -1);
	CHECK(p_mesh.charts[p_corners + 1].kind == SurfaceKind::Ceiling);
	CHECK(p_mesh.charts[p_corners + 1].wall_index == -1);
	for (size_t t = 0; t < triangle_count(p_mesh); ++t) {
		for (int c = 0; c < 3; ++c) {
			CHECK(p_mesh.vertex_charts[p_mesh.indices[3 * t + c]] == p_mesh.triangle_charts[t]);
		}
	}
}

// Welds equal positions, then checks every edge is used exactly twice, once in
// each direction, and that V - E + F = 2 (a closed genus-0 surface).
void check_closed(const RoomMesh &p_mesh) {
	constexpr double weld_grid_m = 1e-5;
	std::map<std::tuple<long long, long long, long long>, int> ids;
	std::vector<int> welded(p_mesh.positions.size());
	for (size_t i = 0; i < p_mesh.positions.size(); ++i) {
		const Vec3f &p = p_mesh.positions[i];
		const auto key = std::make_tuple(std::llround(p.x / weld_grid_m), std::llround(p.y / weld_grid_m), std::llround(p.z / weld_grid_m));
		welded[i] = ids.emplace(key, int(ids.size())).first->second;
	}
	std::map<std::pair<int, int>, int> directed;
	for (size_t t = 0; t < triangle_count(p_mesh); ++t) {
		const int v[3] = { welded[p_mesh.indices[3 * t]], welded[p_mesh.indices[3 * t + 1]], welded[p_mesh.indices[3 * t + 2]] };
		CHECK(v[0] != v[1]);
		CHECK(v[1] != v[2]);
		CHECK(v[2] != v[0]);
		for (int c = 0; c < 3; ++c) {
			++directed[{ v[c], v[(c + 1) % 3] }];
		}
	}
	size_t undirected_edges = 0;
	for (const auto &[edge, count] : directed) {
		CHECK(count == 1); // Used once in this direction...
		const auto twin = directed.find({ edge.second, edge.first });
		CHECK((twin != directed.end() && twin->second == 1)); // ...and once the other way.
		if (edge.first < edge.second) {
			++undirected_edges;
		}
	}
	CHECK(directed.size() == 2 * undirected_edges);
	CHECK(ids.size() == 2 * p_mesh.floorplan.points.size()); // Only the prism's corners.
	CHECK(int(ids.size()) - int(undirected_edges) + int(triangle_count(p_mesh)) == 2);
}

void check_inward_normals(const RoomMesh &p_mesh) {
	const double height = p_mesh.floorplan.ceiling_height_m;
	for (size_t t = 0; t < triangle_count(p_mesh); ++t) {
		const V3 a = corner(p_mesh, t, 0);
		const V3 b = corner(p_mesh, t, 1);
		const V3 c = corner(p_mesh, t, 2);
		const V3 stored = to_v3(p_mesh.normals[p_mesh.indices[3 * t]]);
		CHECK(length(stored) == doctest::Approx(1.0).epsilon(1e-6));
		for (int k = 1; k < 3; ++k) {
			const V3 other = to_v3(p_mesh.normals[p_mesh.indices[3 * t + k]]);
			CHECK(dot(other, stored) == doctest::Approx(1.0).epsilon(1e-6)); // Flat per face.
		}
		// Counter-clockwise seen from inside: the winding normal matches the stored one.
		const V3 winding = cross(sub(b, a), sub(c, a));
		CHECK(dot(winding, stored) / length(winding) == doctest::Approx(1.0).epsilon(1e-5));

		constexpr double step_m = 1e-3;
		const V3 probe = { (a.x + b.x + c.x) / 3 + step_m * stored.x, (a.y + b.y + c.y) / 3 + step_m * stored.y,
			(a.z + b.z + c.z) / 3 + step_m * stored.z };
		CHECK(inside_polygon(p_mesh.floorplan.points, probe.x, probe.z));
		CHECK(probe.y > 0.0);
		CHECK(probe.y < height);
	}
}

void check_volume_and_area(const RoomMesh &p_mesh, const Floorplan &p_truth) {
	const double area = polygon_area(p_truth.points);
	const double height = p_truth.ceiling_height_m;
	double six_volume = 0.0;
	double surface = 0.0;
	for (size_t t = 0; t < triangle_count(p_mesh); ++t) {
		const V3 a = corner(p_mesh, t, 0);
		const V3 b = corner(p_mesh, t, 1);
		const V3 c = corner(p_mesh, t, 2);
		six_volume += dot(a, cross(b, c));
		surface += 0.5 * length(cross(sub(b, a), sub(c, a)));
	}
	// Divergence theorem with inward normals gives minus the enclosed volume.
	CHECK(six_volume / 6.0 == doctest::Approx(-area * height).epsilon(1e-6));
	CHECK(surface == doctest::Approx(2.0 * area + polygon_perimeter(p_truth.points) * height).epsilon(1e-6));
}

void check_atlas(const RoomMesh &p_mesh, const RoomMeshOptions &p_options) {
	const int pad = p_options.padding_texels;
	CHECK(p_mesh.atlas_width > 0);
	CHECK(p_mesh.atlas_height > 0);
	CHECK(p_mesh.atlas_width <= p_options.max_atlas_size);
	CHECK(p_mesh.atlas_height <= p_options.max_atlas_size);
	CHECK(p_mesh.texel_size_m == p_options.texel_size_m);

	// Rects: inside the border padding and at least `pad` texels apart.
	for (size_t i = 0; i < p_mesh.charts.size(); ++i) {
		const Chart &a = p_mesh.charts[i];
		CHECK(a.w == std::max(1, int(std::ceil(a.used_w_texels - 1e-6))));
		CHECK(a.h == std::max(1, int(std::ceil(a.used_h_texels - 1e-6))));
		CHECK(a.x >= pad);
		CHECK(a.y >= pad);
		CHECK(a.x + a.w + pad <= p_mesh.atlas_width);
		CHECK(a.y + a.h + pad <= p_mesh.atlas_height);
		for (size_t j = i + 1; j < p_mesh.charts.size(); ++j) {
			const Chart &b = p_mesh.charts[j];
			const bool apart = a.x + a.w + pad <= b.x || b.x + b.w + pad <= a.x || a.y + a.h + pad <= b.y || b.y + b.h + pad <= a.y;
			CHECK(apart);
		}
	}

	for (const Vec2f &uv : p_mesh.uvs) {
		CHECK(uv.x >= 0.0f);
		CHECK(uv.x <= 1.0f);
		CHECK(uv.y >= 0.0f);
		CHECK(uv.y <= 1.0f);
	}

	// Rasterize every triangle at texel centres: no texel may belong to two charts.
	std::vector<int> owner(size_t(p_mesh.atlas_width) * p_mesh.atlas_height, -1);
	size_t conflicts = 0;
	size_t covered = 0;
	constexpr double uv_slack_texels = 1e-3;
	for (size_t t = 0; t < triangle_count(p_mesh); ++t) {
		const int chart_index = p_mesh.triangle_charts[t];
		const Chart &chart = p_mesh.charts[chart_index];
		std::pair<double, double> p[3];
		for (int c = 0; c < 3; ++c) {
			p[c] = corner_pixel(p_mesh, t, c);
			CHECK(p[c].first >= chart.x - uv_slack_texels);
			CHECK(p[c].first <= chart.x + chart.w + uv_slack_texels);
			CHECK(p[c].second >= chart.y - uv_slack_texels);
			CHECK(p[c].second <= chart.y + chart.h + uv_slack_texels);
		}
		const double uv_area = 0.5 * std::abs((p[1].first - p[0].first) * (p[2].second - p[0].second) -
											 (p[2].first - p[0].first) * (p[1].second - p[0].second));
		const V3 a = corner(p_mesh, t, 0);
		const V3 b = corner(p_mesh, t, 1);
		const V3 c = corner(p_mesh, t, 2);
		const double world_area = 0.5 * length(cross(sub(b, a), sub(c, a)));
		// Uniform texel size: uv area in pixels times texel^2 equals the world area.
		CHECK(world_area / (uv_area * p_options.texel_size_m * p_options.texel_size_m) == doctest::Approx(1.0).epsilon(1e-3));

		const int x0 = std::max(0, int(std::floor(std::min({ p[0].first, p[1].first, p[2].first }))));
		const int x1 = std::min(p_mesh.atlas_width - 1, int(std::ceil(std::max({ p[0].first, p[1].first, p[2].first }))));
		const int y0 = std::max(0, int(std::floor(std::min({ p[0].second, p[1].second, p[2].second }))));
		const int y1 = std::min(p_mesh.atlas_height - 1, int(std::ceil(std::max({ p[0].second, p[1].second, p[2].second }))));
		for (int y = y0; y <= y1; ++y) {
			for (int x = x0; x <= x1; ++x) {
				const double px = x + 0.5;
				const double py = y + 0.5;
				double e[3];
				for (int k = 0; k < 3; ++k) {
					const auto &u = p[k];
					const auto &v = p[(k + 1) % 3];
					e[k] = (v.first - u.first) * (py - u.second) - (v.second - u.second) * (px - u.first);
				}
				const bool in = (e[0] >= 0 && e[1] >= 0 && e[2] >= 0) || (e[0] <= 0 && e[1] <= 0 && e[2] <= 0);
				if (!in) {
					continue;
				}
				int &slot = owner[size_t(y) * p_mesh.atlas_width + x];
				if (slot == -1) {
					slot = chart_index;
					++covered;
				} else if (slot != chart_index) {
					++conflicts;
				}
			}
		}
	}
	CHECK(conflicts == 0);
	// The surfaces cover about (total area / texel^2) texels.
	const double expected = (2.0 * polygon_area(p_mesh.floorplan.points) +
									polygon_perimeter(p_mesh.floorplan.points) * p_mesh.floorplan.ceiling_height_m) /
			(p_options.texel_size_m * p_options.texel_size_m);
	CHECK(double(covered) == doctest::Approx(expected).epsilon(0.05));
}

// Vertex UVs and the chart mapping agree: a vertex's pixel maps back to its position.
void check_uv_world_consistency(const RoomMesh &p_mesh) {
	for (size_t v = 0; v < p_mesh.positions.size(); ++v) {
		const Chart &chart = p_mesh.charts[p_mesh.vertex_charts[v]];
		const double px = double(p_mesh.uvs[v].x) * p_mesh.atlas_width - chart.x;
		const double py = double(p_mesh.uvs[v].y) * p_mesh.atlas_height - chart.y;
		const V3 world = { chart.origin_m.x + chart.u_axis_m.x * px + chart.v_axis_m.x * py,
			chart.origin_m.y + chart.u_axis_m.y * px + chart.v_axis_m.y * py,
			chart.origin_m.z + chart.u_axis_m.z * px + chart.v_axis_m.z * py };
		CHECK(length(sub(world, to_v3(p_mesh.positions[v]))) < 1e-4);
	}
}

// Random texels: those on a surface map onto the right plane, inside its bounds.
void check_texel_to_world(const RoomMesh &p_mesh) {
	const std::vector<Vec2> &points = p_mesh.floorplan.points;
	const size_t n = points.size();
	const double height = p_mesh.floorplan.ceiling_height_m;
	std::mt19937 rng(12345);
	std::uniform_int_distribution<int> pick_x(-2, p_mesh.atlas_width + 1);
	std::uniform_int_distribution<int> pick_y(-2, p_mesh.atlas_height + 1);
	int hits = 0;
	for (int sample = 0; sample < 4000; ++sample) {
		const int x = pick_x(rng);
		const int y = pick_y(rng);
		Vec3 point;
		Vec3 normal;
		const int chart_index = find_chart_at_texel(p_mesh, x, y);
		const bool ok = texel_to_world(p_mesh, x, y, &point, &normal);
		if (chart_index < 0) {
			CHECK_FALSE(ok);
			continue;
		}
		if (!ok) {
			continue;
		}
		++hits;
		const Chart &chart = p_mesh.charts[chart_index];
		CHECK(length(sub(to_v3(normal), to_v3(chart.normal))) < 1e-12);
		if (chart.kind == SurfaceKind::Wall) {
			const Vec2 &a = points[chart.wall_index];
			const Vec2 &b = points[(chart.wall_index + 1) % n];
			const double len = std::hypot(b.x - a.x, b.y - a.y);
			const V3 inward = { -(b.y - a.y) / len, 0.0, (b.x - a.x) / len };
			CHECK(length(sub(to_v3(normal), inward)) < 1e-12);
			CHECK(std::abs(dot(sub(to_v3(point), { a.x, 0.0, a.y }), inward)) < 1e-6);
			CHECK(distance_to_segment_2d(a, b, point.x, point.z) < 1e-6);
			CHECK(point.y >= 0.0);
			CHECK(point.y <= height);
			// Texel centre: (x + 0.5) texels along the wall, (y + 0.5) down from the ceiling.
			const double along = ((point.x - a.x) * (b.x - a.x) + (point.z - a.y) * (b.y - a.y)) / len;
			CHECK(along == doctest::Approx((x - chart.x + 0.5) * p_mesh.texel_size_m).epsilon(1e-9));
			CHECK(height - point.y == doctest::Approx((y - chart.y + 0.5) * p_mesh.texel_size_m).epsilon(1e-9));
		} else {
			const bool floor = chart.kind == SurfaceKind::Floor;
			CHECK(point.y == (floor ? 0.0 : height));
			CHECK(normal.y == (floor ? 1.0 : -1.0));
			const bool on_surface = inside_polygon(points, point.x, point.z) || distance_to_boundary_2d(points, point.x, point.z) < 1e-9;
			CHECK(on_surface);
		}
	}
	CHECK(hits > 100);
}

// Counts the texels that map onto the surface of each chart.
std::vector<long> count_surface_texels(const RoomMesh &p_mesh) {
	std::vector<long> counts(p_mesh.charts.size(), 0);
	for (size_t i = 0; i < p_mesh.charts.size(); ++i) {
		const Chart &chart = p_mesh.charts[i];
		for (int y = chart.y; y < chart.y + chart.h; ++y) {
			for (int x = chart.x; x < chart.x + chart.w; ++x) {
				counts[i] += texel_to_world(p_mesh, x, y, nullptr, nullptr) ? 1 : 0;
			}
		}
	}
	return counts;
}

RoomMesh build_and_check(const Floorplan &p_floorplan, const RoomMeshOptions &p_options = RoomMeshOptions()) {
	const RoomMeshResult result = build_room_mesh(p_floorplan, p_options);
	REQUIRE_MESSAGE(result.ok, result.error);
	CHECK(result.error.empty());
	const RoomMesh &mesh = result.mesh;
	CHECK(is_counter_clockwise(mesh.floorplan));
	CHECK(mesh.floorplan.ceiling_height_m == p_floorplan.ceiling_height_m);
	check_array_sizes(mesh, p_floorplan.points.size());
	check_closed(mesh);
	check_inward_normals(mesh);
	check_volume_and_area(mesh, p_floorplan);
	check_atlas(mesh, p_options);
	check_uv_world_consistency(mesh);
	check_texel_to_world(mesh);
	return mesh;
}

} // namespace

TEST_CASE("figure 4 two-room floorplan gives a closed, correctly oriented, uniformly textured prism") {
	const RoomMesh mesh = build_and_check(figure4_two_rooms());
	// Wall 0 runs 3.94 m along x, 2.6 m high: 197 x 130 texels at 2 cm.
	CHECK(mesh.charts[0].w == 197);
	CHECK(mesh.charts[0].h == 130);
	CHECK(mesh.charts[2].w == 6); // The 0.12 m partition end.
	CHECK(mesh.charts[6].w == 400); // The 8 m back wall.
	CHECK(mesh.charts[8].w == 400); // Floor: 8 m x 4.5 m bounding box.
	CHECK(mesh.charts[8].h == 225);
	CHECK(mesh.charts[9].w == 400);
	CHECK(mesh.charts[9].h == 225);
	// Partition end wall faces +z (into the room, away from the wall it hangs from).
	CHECK(mesh.charts[2].normal.z == doctest::Approx(1.0));
}

TEST_CASE("living room and L-shaped room") {
	build_and_check(living_room());
	build_and_check(l_shaped_room());
}

TEST_CASE("clockwise input is normalized and still gives a correct mesh") {
	for (Floorplan floorplan : { figure4_two_rooms(), l_shaped_room(), living_room() }) {
		std::reverse(floorplan.points.begin(), floorplan.points.end());
		REQUIRE_FALSE(is_counter_clockwise(floorplan));
		const RoomMesh mesh = build_and_check(floorplan);
		CHECK(mesh.floorplan.points.size() == floorplan.points.size());
	}
}

TEST_CASE("other texel sizes and padding keep the atlas uniform and non-overlapping") {
	RoomMeshOptions options;
	options.texel_size_m = 0.07; // Extents are not whole numbers of texels.
	options.padding_texels = 0;
	build_and_check(figure4_two_rooms(), options);
	options.texel_size_m = 0.033;
	options.padding_texels = 5;
	build_and_check(l_shaped_room(), options);
}

TEST_CASE("a non-axis-aligned room with a corner in the middle of a wall") {
	Floorplan floorplan;
	// A rotated pentagon-like room with a reflex corner and a straight-through corner (2).
	floorplan.points = { { 0.0, 0.0 }, { 2.0, 1.0 }, { 4.0, 2.0 }, { 3.0, 4.5 }, { 1.7, 2.2 }, { -0.5, 3.0 } };
	floorplan.ceiling_height_m = 2.75;
	build_and_check(floorplan);
}

TEST_CASE("texel_to_world covers exactly the surfaces") {
	const RoomMesh mesh = build_and_check(figure4_two_rooms());
	const std::vector<long> counts = count_surface_texels(mesh);
	// Walls: whole-texel extents, every texel centre lies on the wall.
	CHECK(counts[0] == 197 * 130);
	CHECK(counts[2] == 6 * 130);
	CHECK(counts[6] == 400 * 130);
	// Floor and ceiling: 35.64 m^2 = 89100 texels; the partition slot (6 x 150) is excluded.
	CHECK(counts[8] == 400 * 225 - 6 * 150);
	CHECK(counts[9] == 400 * 225 - 6 * 150);
	// Padding and outside the atlas.
	CHECK_FALSE(texel_to_world(mesh, 0, 0, nullptr, nullptr));
	CHECK_FALSE(texel_to_world(mesh, -1, 5, nullptr, nullptr));
	CHECK_FALSE(texel_to_world(mesh, mesh.atlas_width, mesh.atlas_height, nullptr, nullptr));
	CHECK(find_chart_at_texel(mesh, 0, 0) == -1);

	// A texel centre in the rounding margin of a chart is not on the surface.
	RoomMeshOptions options;
	options.texel_size_m = 0.07;
	const RoomMesh coarse = build_and_check(living_room(), options); // 5 m = 71.43 texels -> 72.
	const Chart &wall = coarse.charts[0];
	REQUIRE(wall.w == 72);
	CHECK(texel_to_world(coarse, wall.x + 70, wall.y, nullptr, nullptr));
	CHECK_FALSE(texel_to_world(coarse, wall.x + 71, wall.y, nullptr, nullptr));
	CHECK(find_chart_at_texel(coarse, wall.x + 71, wall.y) == 0);
}

TEST_CASE("chart orientation: not mirrored when seen from inside") {
	const RoomMesh mesh = build_and_check(living_room());
	for (const Chart &chart : mesh.charts) {
		// Looking at the surface against its normal, with up = v_axis reversed,
		// right must be u_axis: right x up points back at the viewer (the normal).
		const V3 up = { -chart.v_axis_m.x, -chart.v_axis_m.y, -chart.v_axis_m.z };
		const V3 back = cross(to_v3(chart.u_axis_m), up);
		CHECK(dot(back, to_v3(chart.normal)) == doctest::Approx(mesh.texel_size_m * mesh.texel_size_m));
	}
	// Walls have the ceiling at the top of the chart.
	CHECK(mesh.charts[0].origin_m.y == doctest::Approx(2.5));
	CHECK(mesh.charts[0].v_axis_m.y < 0.0);
}

TEST_CASE("invalid floorplans and options are reported, not thrown") {
	Floorplan bow_tie;
	bow_tie.points = { { 0, 0 }, { 2, 2 }, { 2, 0 }, { 0, 2 } };
	bow_tie.ceiling_height_m = 2.5;
	RoomMeshResult result = build_room_mesh(bow_tie);
	CHECK_FALSE(result.ok);
	CHECK(result.error == "invalid floorplan: floorplan edge 0 (points 0-1) crosses edge 2 (points 2-3)");

	Floorplan low = living_room();
	low.ceiling_height_m = -1.0;
	result = build_room_mesh(low);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("ceiling height must be above 0 m, got -1") != std::string::npos);

	RoomMeshOptions options;
	options.texel_size_m = 0.0;
	result = build_room_mesh(living_room(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("texel_size_m") != std::string::npos);

	options = RoomMeshOptions();
	options.padding_texels = -1;
	result = build_room_mesh(living_room(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("padding_texels") != std::string::npos);
}

TEST_CASE("an atlas larger than max_atlas_size is an error") {
	RoomMeshOptions options;
	options.max_atlas_size = 512; // The 8 m walls alone need 404 texels; all charts cannot fit.
	RoomMeshResult result = build_room_mesh(figure4_two_rooms(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("max_atlas_size 512") != std::string::npos);

	options.max_atlas_size = 300; // Narrower than one 8 m wall.
	result = build_room_mesh(figure4_two_rooms(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("max_atlas_size 300") != std::string::npos);

	options = RoomMeshOptions();
	options.texel_size_m = 1e-9; // Absurd resolution must not overflow int sizes.
	result = build_room_mesh(figure4_two_rooms(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("max_atlas_size") != std::string::npos);

	// 1e-300 m once printed an overflowed texel count (-9223372036854775808); the count stays a
	// positive number in the message.
	options.texel_size_m = 1e-300;
	result = build_room_mesh(figure4_two_rooms(), options);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("e+30") != std::string::npos);
	CHECK(result.error.find('-') == std::string::npos);

	// The default fits easily.
	CHECK(build_room_mesh(figure4_two_rooms()).ok);
}

TEST_CASE("the packed atlas is reasonably tight") {
	const RoomMesh mesh = build_and_check(figure4_two_rooms());
	long long used = 0;
	for (const Chart &chart : mesh.charts) {
		used += (long long)chart.w * chart.h;
	}
	const double fill = double(used) / (double(mesh.atlas_width) * mesh.atlas_height);
	CHECK(fill > 0.6);
	MESSAGE("figure 4 atlas: " << mesh.atlas_width << " x " << mesh.atlas_height << ", fill " << fill);
}
