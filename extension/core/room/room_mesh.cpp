#include "room_mesh.h"

#include "polygon_triangulation.h"
#include "room_cgal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <exception>
#include <numeric>

namespace roomprobe {

namespace {

using room_cgal::Kernel;

// Lets an extent that is an integer number of texels up to rounding noise
// (e.g. 5 m / 0.02 m = 250.00000000000003) take exactly that many texels.
constexpr double TEXEL_ROUNDING_SLACK = 1e-6;

// Each packing attempt widens the atlas by this factor; the smallest atlas wins.
constexpr double PACK_WIDTH_GROWTH = 1.05;

struct Rect {
	int x = 0;
	int y = 0;
};

struct Packing {
	std::vector<Rect> rects; // Per chart, same order as the input charts.
	int width = 0;
	int height = 0;
};

Vec3 operator+(const Vec3 &p_a, const Vec3 &p_b) {
	return { p_a.x + p_b.x, p_a.y + p_b.y, p_a.z + p_b.z };
}

Vec3 operator-(const Vec3 &p_a, const Vec3 &p_b) {
	return { p_a.x - p_b.x, p_a.y - p_b.y, p_a.z - p_b.z };
}

Vec3 operator*(const Vec3 &p_a, double p_s) {
	return { p_a.x * p_s, p_a.y * p_s, p_a.z * p_s };
}

double dot(const Vec3 &p_a, const Vec3 &p_b) {
	return p_a.x * p_b.x + p_a.y * p_b.y + p_a.z * p_b.z;
}

Vec3f to_float(const Vec3 &p_v) {
	return { float(p_v.x), float(p_v.y), float(p_v.z) };
}

int texels_for(double p_extent_texels) {
	return std::max(1, int(std::ceil(p_extent_texels - TEXEL_ROUNDING_SLACK)));
}

// Shelf packing at a fixed atlas width: charts in p_order fill rows left to
// right; a chart that does not fit starts a new row below the tallest one so far.
Packing pack_shelves(const std::vector<Chart> &p_charts, const std::vector<std::size_t> &p_order, int p_width, int p_padding) {
	Packing packing;
	packing.rects.resize(p_charts.size());
	int cursor_x = p_padding;
	int shelf_y = p_padding;
	int shelf_height = 0;
	int used_width = 0;
	for (std::size_t index : p_order) {
		const Chart &chart = p_charts[index];
		if (cursor_x > p_padding && cursor_x + chart.w + p_padding > p_width) {
			shelf_y += shelf_height + p_padding;
			cursor_x = p_padding;
			shelf_height = 0;
		}
		packing.rects[index] = { cursor_x, shelf_y };
		cursor_x += chart.w + p_padding;
		used_width = std::max(used_width, cursor_x);
		shelf_height = std::max(shelf_height, chart.h);
	}
	packing.width = used_width;
	packing.height = shelf_y + shelf_height + p_padding;
	return packing;
}

// Tries a range of atlas widths and keeps the packing with the smallest area
// (then the squarest) that fits within p_max_size. Chart counts are small, so
// the brute force costs nothing.
bool pack_atlas(std::vector<Chart> &r_charts, int p_padding, int p_max_size, int *r_width, int *r_height, std::string *r_error) {
	std::vector<std::size_t> order(r_charts.size());
	std::iota(order.begin(), order.end(), std::size_t(0));
	// Tallest first keeps shelves full; ties by width, then index, for determinism.
	std::sort(order.begin(), order.end(), [&](std::size_t p_a, std::size_t p_b) {
		const Chart &a = r_charts[p_a];
		const Chart &b = r_charts[p_b];
		if (a.h != b.h) {
			return a.h > b.h;
		}
		if (a.w != b.w) {
			return a.w > b.w;
		}
		return p_a < p_b;
	});

	long long widest = 0;
	long long widths_sum = p_padding;
	for (const Chart &chart : r_charts) {
		widest = std::max<long long>(widest, chart.w);
		widths_sum += chart.w + p_padding;
	}
	const long long min_width = widest + 2LL * p_padding;
	if (min_width > p_max_size) {
		*r_error = "the widest chart needs an atlas " + std::to_string(min_width) + " texels wide, above max_atlas_size " +
				std::to_string(p_max_size) + "; use a larger texel_size_m";
		return false;
	}

	bool found = false;
	Packing best;
	long long width = min_width;
	const long long last_width = std::min<long long>(widths_sum, p_max_size);
	while (true) {
		const Packing packing = pack_shelves(r_charts, order, int(width), p_padding);
		if (packing.height <= p_max_size) {
			const long long area = (long long)packing.width * packing.height;
			const long long best_area = (long long)best.width * best.height;
			const bool squarer = std::max(packing.width, packing.height) < std::max(best.width, best.height);
			if (!found || area < best_area || (area == best_area && squarer)) {
				best = packing;
				found = true;
			}
		}
		if (width >= last_width) {
			break;
		}
		width = std::min(last_width, std::max(width + 1, (long long)std::ceil(double(width) * PACK_WIDTH_GROWTH)));
	}
	if (!found) {
		const Packing widest_try = pack_shelves(r_charts, order, int(last_width), p_padding);
		*r_error = "the charts need an atlas of about " + std::to_string(widest_try.width) + " x " +
				std::to_string(widest_try.height) + " texels, above max_atlas_size " + std::to_string(p_max_size) +
				"; use a larger texel_size_m";
		return false;
	}
	for (std::size_t i = 0; i < r_charts.size(); ++i) {
		r_charts[i].x = best.rects[i].x;
		r_charts[i].y = best.rects[i].y;
	}
	*r_width = best.width;
	*r_height = best.height;
	return true;
}

// Continuous atlas pixel coordinates of a world point on the chart's plane.
Vec2 world_to_pixel(const Chart &p_chart, double p_texel, const Vec3 &p_point) {
	const Vec3 offset = p_point - p_chart.origin_m;
	const double inv_texel_sq = 1.0 / (p_texel * p_texel);
	return { p_chart.x + dot(offset, p_chart.u_axis_m) * inv_texel_sq,
		p_chart.y + dot(offset, p_chart.v_axis_m) * inv_texel_sq };
}

// Appends one vertex of p_chart_index and returns its index.
uint32_t add_vertex(RoomMesh &r_mesh, int p_chart_index, const Vec3 &p_point) {
	const Chart &chart = r_mesh.charts[p_chart_index];
	const Vec2 pixel = world_to_pixel(chart, r_mesh.texel_size_m, p_point);
	r_mesh.positions.push_back(to_float(p_point));
	r_mesh.normals.push_back(to_float(chart.normal));
	r_mesh.uvs.push_back({ float(pixel.x / r_mesh.atlas_width), float(pixel.y / r_mesh.atlas_height) });
	r_mesh.vertex_charts.push_back(p_chart_index);
	return uint32_t(r_mesh.positions.size() - 1);
}

void add_triangle(RoomMesh &r_mesh, int p_chart_index, uint32_t p_a, uint32_t p_b, uint32_t p_c) {
	r_mesh.indices.insert(r_mesh.indices.end(), { p_a, p_b, p_c });
	r_mesh.triangle_charts.push_back(p_chart_index);
}

// A texel count for a message. A tiny texel_size_m makes counts beyond int64_t (1e-300 m once
// printed -9223372036854775808), so large ones are written as a double.
std::string texel_count_text(double p_texels) {
	if (p_texels < 1e15) {
		return std::to_string(int64_t(std::ceil(p_texels)));
	}
	char text[32];
	std::snprintf(text, sizeof(text), "%.3g", p_texels);
	return text;
}

std::string check_options(const RoomMeshOptions &p_options) {
	if (!std::isfinite(p_options.texel_size_m) || p_options.texel_size_m <= 0.0) {
		return "texel_size_m must be a finite number above 0";
	}
	if (p_options.padding_texels < 0) {
		return "padding_texels must be 0 or more, got " + std::to_string(p_options.padding_texels);
	}
	if (p_options.max_atlas_size < 1) {
		return "max_atlas_size must be at least 1, got " + std::to_string(p_options.max_atlas_size);
	}
	return std::string();
}

RoomMeshResult build_room_mesh_unguarded(const Floorplan &p_floorplan, const RoomMeshOptions &p_options) {
	RoomMeshResult result;
	const std::string options_error = check_options(p_options);
	if (!options_error.empty()) {
		result.error = "invalid room mesh options: " + options_error;
		return result;
	}
	const FloorplanCheck check = check_floorplan(p_floorplan);
	if (!check.ok) {
		result.error = "invalid floorplan: " + check.message;
		return result;
	}

	RoomMesh &mesh = result.mesh;
	mesh.floorplan = normalized(p_floorplan);
	mesh.texel_size_m = p_options.texel_size_m;
	const std::vector<Vec2> &points = mesh.floorplan.points;
	const std::size_t n = points.size();
	const double height = mesh.floorplan.ceiling_height_m;
	const double texel = p_options.texel_size_m;

	// Chart extents; positions in the atlas come from the packer below.
	Vec2 low = points[0];
	Vec2 high = points[0];
	for (const Vec2 &point : points) {
		low = { std::min(low.x, point.x), std::min(low.y, point.y) };
		high = { std::max(high.x, point.x), std::max(high.y, point.y) };
	}
	for (std::size_t i = 0; i < n; ++i) {
		const Vec2 &from = points[i];
		const Vec2 &to = points[(i + 1) % n];
		const double length = std::hypot(to.x - from.x, to.y - from.y);
		const Vec3 along = { (to.x - from.x) / length, 0.0, (to.y - from.y) / length };
		Chart wall;
		wall.kind = SurfaceKind::Wall;
		wall.wall_index = int(i);
		wall.used_w_texels = length / texel;
		wall.used_h_texels = height / texel;
		wall.origin_m = { from.x, height, from.y };
		wall.u_axis_m = along * texel;
		wall.v_axis_m = { 0.0, -texel, 0.0 };
		// The interior lies to the left of the edge in the (x, z) plane.
		wall.normal = { -along.z, 0.0, along.x };
		mesh.charts.push_back(wall);
	}
	Chart floor;
	floor.kind = SurfaceKind::Floor;
	floor.used_w_texels = (high.x - low.x) / texel;
	floor.used_h_texels = (high.y - low.y) / texel;
	floor.origin_m = { low.x, 0.0, low.y };
	floor.u_axis_m = { texel, 0.0, 0.0 };
	floor.v_axis_m = { 0.0, 0.0, texel };
	floor.normal = { 0.0, 1.0, 0.0 };
	mesh.charts.push_back(floor);
	Chart ceiling = floor;
	ceiling.kind = SurfaceKind::Ceiling;
	ceiling.origin_m = { low.x, height, high.y };
	ceiling.v_axis_m = { 0.0, 0.0, -texel };
	ceiling.normal = { 0.0, -1.0, 0.0 };
	mesh.charts.push_back(ceiling);

	for (Chart &chart : mesh.charts) {
		// Reject before converting to int, so huge rooms cannot overflow.
		if (chart.used_w_texels > p_options.max_atlas_size || chart.used_h_texels > p_options.max_atlas_size) {
			result.error = std::string("the ") + surface_kind_name(chart.kind) + " chart needs " +
					texel_count_text(chart.used_w_texels) + " x " + texel_count_text(chart.used_h_texels) +
					" texels, above max_atlas_size " +
					std::to_string(p_options.max_atlas_size) + "; use a larger texel_size_m";
			return result;
		}
		chart.w = texels_for(chart.used_w_texels);
		chart.h = texels_for(chart.used_h_texels);
	}
	if (!pack_atlas(mesh.charts, p_options.padding_texels, p_options.max_atlas_size, &mesh.atlas_width, &mesh.atlas_height, &result.error)) {
		return result;
	}

	std::vector<std::size_t> triangles;
	if (!triangulate_polygon(points, &triangles, &result.error)) {
		return result;
	}

	for (std::size_t i = 0; i < n; ++i) {
		const Vec2 &from = points[i];
		const Vec2 &to = points[(i + 1) % n];
		const int chart = int(i);
		// Corners: a, b on the floor, c, d at the ceiling; a -> b -> c is
		// counter-clockwise seen from inside.
		const uint32_t a = add_vertex(mesh, chart, { from.x, 0.0, from.y });
		const uint32_t b = add_vertex(mesh, chart, { to.x, 0.0, to.y });
		const uint32_t c = add_vertex(mesh, chart, { to.x, height, to.y });
		const uint32_t d = add_vertex(mesh, chart, { from.x, height, from.y });
		add_triangle(mesh, chart, a, b, c);
		add_triangle(mesh, chart, a, c, d);
	}

	const int floor_chart = int(n);
	const int ceiling_chart = int(n + 1);
	const uint32_t floor_base = uint32_t(mesh.positions.size());
	for (const Vec2 &point : points) {
		add_vertex(mesh, floor_chart, { point.x, 0.0, point.y });
	}
	const uint32_t ceiling_base = uint32_t(mesh.positions.size());
	for (const Vec2 &point : points) {
		add_vertex(mesh, ceiling_chart, { point.x, height, point.y });
	}
	for (std::size_t t = 0; t < triangles.size(); t += 3) {
		const uint32_t a = uint32_t(triangles[t]);
		const uint32_t b = uint32_t(triangles[t + 1]);
		const uint32_t c = uint32_t(triangles[t + 2]);
		// Counter-clockwise in (x, z) faces down (-Y) in the right-handed
		// world, which suits the ceiling; the floor must face up, so flip it.
		add_triangle(mesh, floor_chart, floor_base + a, floor_base + c, floor_base + b);
		add_triangle(mesh, ceiling_chart, ceiling_base + a, ceiling_base + b, ceiling_base + c);
	}
	result.ok = true;
	return result;
}

} // namespace

RoomMeshResult build_room_mesh(const Floorplan &p_floorplan, const RoomMeshOptions &p_options) {
	// CGAL's predicates report failures by throwing; the Godot side is usually built without
	// exceptions, so none may leave the core.
	try {
		return build_room_mesh_unguarded(p_floorplan, p_options);
	} catch (const std::exception &e) {
		RoomMeshResult result;
		result.error = std::string("building the room mesh failed: ") + e.what();
		return result;
	}
}

int find_chart_at_texel(const RoomMesh &p_mesh, int p_x, int p_y) {
	for (std::size_t i = 0; i < p_mesh.charts.size(); ++i) {
		const Chart &chart = p_mesh.charts[i];
		if (p_x >= chart.x && p_x < chart.x + chart.w && p_y >= chart.y && p_y < chart.y + chart.h) {
			return int(i);
		}
	}
	return -1;
}

bool texel_to_world(const RoomMesh &p_mesh, int p_x, int p_y, Vec3 *r_point, Vec3 *r_normal) {
	const int index = find_chart_at_texel(p_mesh, p_x, p_y);
	if (index < 0) {
		return false;
	}
	const Chart &chart = p_mesh.charts[index];
	const double local_x = p_x + 0.5 - chart.x;
	const double local_y = p_y + 0.5 - chart.y;
	if (local_x > chart.used_w_texels || local_y > chart.used_h_texels) {
		return false; // In the margin left by rounding the chart up to whole texels.
	}
	const Vec3 point = chart.origin_m + chart.u_axis_m * local_x + chart.v_axis_m * local_y;
	if (chart.kind != SurfaceKind::Wall) {
		std::vector<room_cgal::Point> polygon;
		polygon.reserve(p_mesh.floorplan.points.size());
		for (const Vec2 &corner : p_mesh.floorplan.points) {
			polygon.push_back(room_cgal::to_cgal(corner));
		}
		try {
			const CGAL::Bounded_side side = CGAL::bounded_side_2(polygon.begin(), polygon.end(), room_cgal::Point(point.x, point.z), Kernel());
			if (side == CGAL::ON_UNBOUNDED_SIDE) {
				return false;
			}
		} catch (const std::exception &) {
			return false; // Only for a hand-edited, invalid mesh.floorplan; keep exceptions inside the core.
		}
	}
	if (r_point) {
		*r_point = point;
	}
	if (r_normal) {
		*r_normal = chart.normal;
	}
	return true;
}

const char *surface_kind_name(SurfaceKind p_kind) {
	switch (p_kind) {
		case SurfaceKind::Wall:
			return "wall";
		case SurfaceKind::Floor:
			return "floor";
		case SurfaceKind::Ceiling:
			return "ceiling";
	}
	return "unknown";
}

} // namespace roomprobe
