#include "coarse_render.h"

#include <glm/geometric.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace roomprobe {

namespace {

glm::dvec3 to_glm(const Vec3 &p_v) {
	return glm::dvec3(p_v.x, p_v.y, p_v.z);
}

double cross2(double p_ax, double p_ay, double p_bx, double p_by) {
	return p_ax * p_by - p_ay * p_bx;
}

// Crossing-number test in the floorplan's (x, z) plane.
bool inside_polygon(const std::vector<Vec2> &p_points, double p_x, double p_z) {
	bool inside = false;
	const size_t n = p_points.size();
	for (size_t i = 0, j = n - 1; i < n; j = i++) {
		const Vec2 &a = p_points[i];
		const Vec2 &b = p_points[j];
		if ((a.y > p_z) != (b.y > p_z)) {
			const double x = a.x + (p_z - a.y) * (b.x - a.x) / (b.y - a.y);
			if (p_x < x) {
				inside = !inside;
			}
		}
	}
	return inside;
}

} // namespace

bool intersect_room(const RoomMesh &p_mesh, const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, RoomRayHit *r_hit) {
	const std::vector<Vec2> &points = p_mesh.floorplan.points;
	const size_t n = points.size();
	const double height = p_mesh.floorplan.ceiling_height_m;
	const double length = glm::length(p_direction);
	if (n < 3 || p_mesh.charts.size() < n + 2 || !(length > 0.0)) {
		return false;
	}
	const glm::dvec3 d = p_direction / length;
	const double t_min = 1e-12;
	// Rays along an edge where two surfaces meet (a wall's top or bottom, a corner) must not slip
	// between both: walls accept hits this little beyond their ends and height.
	const double slack = 1e-9;
	double best = std::numeric_limits<double>::infinity();
	int best_chart = -1;

	// Walls: segments points[i] -> points[i + 1] in (x, z), hit between floor and ceiling.
	for (size_t i = 0; i < n; i++) {
		const Vec2 &a = points[i];
		const Vec2 &b = points[(i + 1) % n];
		const double ex = b.x - a.x;
		const double ez = b.y - a.y;
		const double denom = cross2(d.x, d.z, ex, ez);
		if (denom == 0.0) {
			continue; // parallel to the wall (or straight up / down)
		}
		const double wx = a.x - p_origin.x;
		const double wz = a.y - p_origin.z;
		const double t = cross2(wx, wz, ex, ez) / denom;
		const double s = cross2(wx, wz, d.x, d.z) / denom;
		if (t <= t_min || t >= best || s < -slack || s > 1.0 + slack) {
			continue;
		}
		const double y = p_origin.y + t * d.y;
		if (y < -slack || y > height + slack) {
			continue;
		}
		best = t;
		best_chart = int(i);
	}
	// Floor (y = 0) and ceiling (y = height).
	if (d.y != 0.0) {
		const bool down = d.y < 0.0;
		const double t = ((down ? 0.0 : height) - p_origin.y) / d.y;
		if (t > t_min && t < best && inside_polygon(points, p_origin.x + t * d.x, p_origin.z + t * d.z)) {
			best = t;
			best_chart = int(n) + (down ? 0 : 1);
		}
	}
	if (best_chart < 0) {
		return false;
	}
	const Chart &chart = p_mesh.charts[size_t(best_chart)];
	const glm::dvec3 point = p_origin + best * d;
	const glm::dvec3 offset = point - to_glm(chart.origin_m);
	const glm::dvec3 u = to_glm(chart.u_axis_m);
	const glm::dvec3 v = to_glm(chart.v_axis_m);
	r_hit->distance = best;
	r_hit->point = point;
	r_hit->chart = best_chart;
	r_hit->atlas = glm::dvec2(chart.x + glm::dot(offset, u) / glm::dot(u, u), chart.y + glm::dot(offset, v) / glm::dot(v, v));
	return true;
}

CoarseCubemapRenderer::CoarseCubemapRenderer(const RoomMesh &p_mesh) :
		mesh(p_mesh), on_surface(size_t(std::max(0, p_mesh.atlas_width)) * size_t(std::max(0, p_mesh.atlas_height)), 0) {
	const int width = mesh.atlas_width;
	tbb::parallel_for(tbb::blocked_range<int>(0, std::max(0, mesh.atlas_height)), [&](const tbb::blocked_range<int> &p_rows) {
		for (int y = p_rows.begin(); y != p_rows.end(); y++) {
			for (int x = 0; x < width; x++) {
				on_surface[size_t(y) * size_t(width) + size_t(x)] = texel_to_world(mesh, x, y, nullptr, nullptr) ? 1 : 0;
			}
		}
	});
}

bool CoarseCubemapRenderer::texel_on_surface(int p_x, int p_y) const {
	if (p_x < 0 || p_y < 0 || p_x >= mesh.atlas_width || p_y >= mesh.atlas_height) {
		return false;
	}
	return on_surface[size_t(p_y) * size_t(mesh.atlas_width) + size_t(p_x)] != 0;
}

CoarseCubemapRenderer::Taps CoarseCubemapRenderer::texel_taps(int p_chart, const glm::dvec2 &p_atlas) const {
	const Chart &chart = mesh.charts[size_t(p_chart)];
	// The last texel whose centre lies within the chart's used extent, per axis.
	const int last_x = chart.x + std::clamp(int(std::floor(chart.used_w_texels - 0.5)), 0, std::max(0, chart.w - 1));
	const int last_y = chart.y + std::clamp(int(std::floor(chart.used_h_texels - 0.5)), 0, std::max(0, chart.h - 1));
	// Texel-centre coordinates, clamped to the chart.
	const double fx = std::clamp(p_atlas.x - 0.5, double(chart.x), double(last_x));
	const double fy = std::clamp(p_atlas.y - 0.5, double(chart.y), double(last_y));
	const int x0 = int(std::floor(fx));
	const int y0 = int(std::floor(fy));
	const int x1 = std::min(x0 + 1, last_x);
	const int y1 = std::min(y0 + 1, last_y);
	const double ax = fx - x0;
	const double ay = fy - y0;
	const int xs[4] = { x0, x1, x0, x1 };
	const int ys[4] = { y0, y0, y1, y1 };
	const double ws[4] = { (1.0 - ax) * (1.0 - ay), ax * (1.0 - ay), (1.0 - ax) * ay, ax * ay };
	const auto index = [&](int p_x, int p_y) { return uint32_t(p_y) * uint32_t(mesh.atlas_width) + uint32_t(p_x); };
	// The used taps: on the surface, with a weight.
	int used[4];
	int count = 0;
	double weight = 0.0;
	for (int i = 0; i < 4; i++) {
		if (ws[i] > 0.0 && texel_on_surface(xs[i], ys[i])) {
			used[count++] = i;
			weight += ws[i];
		}
	}
	Taps taps;
	taps.hit = 1.0f;
	if (count == 0) {
		// No surface texel among the taps (a sliver of floor or ceiling between texel centres):
		// the nearest tap.
		taps.index[0] = taps.index[1] = taps.index[2] = taps.index[3] = index(ax < 0.5 ? x0 : x1, ay < 0.5 ? y0 : y1);
		return taps;
	}
	// The first used tap, then the others' share of the weight; unused ones repeat the first
	// (weight 0: texels off the surface are never read).
	for (int k = 0; k < 4; k++) {
		const int i = used[k < count ? k : 0];
		taps.index[k] = index(xs[i], ys[i]);
		if (k > 0 && k < count) {
			taps.weight[k - 1] = float(ws[i] / weight);
		}
	}
	return taps;
}

namespace {

// The atlas as one array of texels (a copy only when the Mat is a view with gaps).
cv::Mat continuous(const cv::Mat &p_atlas_color) {
	return p_atlas_color.isContinuous() ? p_atlas_color : p_atlas_color.clone();
}

} // namespace

// The taps' weighted mean of an atlas of N-channel float texels, as the first tap plus the
// others' weighted differences from it: where the taps agree the result is their value exactly
// (a chart id, a mask, a flat colour), and no branch but the miss.
template <int N>
cv::Vec<float, N> CoarseCubemapRenderer::gather(const cv::Vec<float, N> *p_atlas, const Taps &p_taps) {
	cv::Vec<float, N> out = cv::Vec<float, N>::all(0.0f);
	if (p_taps.hit == 0.0f) {
		return out; // the ray hit nothing
	}
	const cv::Vec<float, N> &c0 = p_atlas[p_taps.index[0]];
	const cv::Vec<float, N> &c1 = p_atlas[p_taps.index[1]];
	const cv::Vec<float, N> &c2 = p_atlas[p_taps.index[2]];
	const cv::Vec<float, N> &c3 = p_atlas[p_taps.index[3]];
	for (int k = 0; k < N; k++) {
		out[k] = c0[k] + p_taps.weight[0] * (c1[k] - c0[k]) + p_taps.weight[1] * (c2[k] - c0[k]) + p_taps.weight[2] * (c3[k] - c0[k]);
	}
	return out;
}

template <int N>
void CoarseCubemapRenderer::gather_faces(const Lookup &p_lookup, const cv::Mat &p_atlas, std::array<cv::Mat, 6> *r_faces) {
	const int size = p_lookup.size;
	const cv::Mat whole = continuous(p_atlas); // held: it may be a copy
	const cv::Vec<float, N> *atlas = whole.ptr<cv::Vec<float, N>>();
	tbb::parallel_for(tbb::blocked_range<int>(0, 6 * size), [&](const tbb::blocked_range<int> &p_rows) {
		for (int row = p_rows.begin(); row != p_rows.end(); row++) {
			cv::Vec<float, N> *out = (*r_faces)[size_t(row / size)].ptr<cv::Vec<float, N>>(row % size);
			const Taps *in = &p_lookup.taps[size_t(row) * size_t(size)];
			for (int u = 0; u < size; u++) {
				out[u] = gather(atlas, in[u]);
			}
		}
	});
}

std::shared_ptr<const CoarseCubemapRenderer::Lookup> CoarseCubemapRenderer::lookup(const glm::dvec3 &p_position, int p_size,
		const glm::dquat &p_room_from_world) const {
	{
		const std::lock_guard<std::mutex> lock(lookup_mutex);
		for (auto it = lookups.begin(); it != lookups.end(); ++it) {
			if ((*it)->size == p_size && (*it)->position == p_position && (*it)->room_from_world == p_room_from_world) {
				lookups.splice(lookups.begin(), lookups, it);
				return lookups.front();
			}
		}
	}
	auto built = std::make_shared<Lookup>();
	built->position = p_position;
	built->size = p_size;
	built->room_from_world = p_room_from_world;
	const glm::dmat3 turn = glm::mat3_cast(p_room_from_world);
	built->taps.resize(size_t(6) * size_t(p_size) * size_t(p_size));
	built->distance_m.assign(built->taps.size(), 0.0f);
	tbb::parallel_for(tbb::blocked_range<int>(0, 6 * p_size), [&](const tbb::blocked_range<int> &p_rows) {
		for (int row = p_rows.begin(); row != p_rows.end(); row++) {
			const int face = row / p_size;
			const int v = row % p_size;
			Taps *out = &built->taps[size_t(row) * size_t(p_size)];
			float *distance = &built->distance_m[size_t(row) * size_t(p_size)];
			for (int u = 0; u < p_size; u++) {
				RoomRayHit hit;
				if (intersect_room(mesh, p_position, turn * cubemap_direction(face, u, v, p_size), &hit)) {
					out[u] = texel_taps(hit.chart, hit.atlas);
					distance[u] = float(hit.distance);
				}
			}
		}
	});
	const std::lock_guard<std::mutex> lock(lookup_mutex);
	lookups.push_front(built);
	while (int(lookups.size()) > MAX_CACHED_LOOKUPS) {
		lookups.pop_back();
	}
	return built;
}

void CoarseCubemapRenderer::set_compute(std::shared_ptr<ComputeDevice> p_device) {
	static_assert(sizeof(Taps) == 32 && std::is_trivially_copyable_v<Taps>, "coarse_gather.comp's Taps");
	const std::lock_guard<std::mutex> lock(gpu_mutex);
	gpu.reset();
	gpu_problem.clear();
	if (p_device) {
		std::string error;
		gpu = CoarseGatherGpu::create(std::move(p_device), &error);
		if (!gpu) {
			gpu_problem = "the coarse render on the CPU (the device's kernel: " + error + ")";
		}
	}
}

bool CoarseCubemapRenderer::gathers_on_gpu() const {
	const std::lock_guard<std::mutex> lock(gpu_mutex);
	return gpu != nullptr;
}

std::string CoarseCubemapRenderer::compute_problem() const {
	const std::lock_guard<std::mutex> lock(gpu_mutex);
	return gpu_problem;
}

bool CoarseCubemapRenderer::gather_on_gpu(const std::shared_ptr<const Lookup> &p_lookup, const cv::Mat &p_atlas, bool p_published,
		std::array<cv::Mat, 6> *r_faces) const {
	const std::lock_guard<std::mutex> lock(gpu_mutex);
	if (!gpu) {
		return false;
	}
	std::string error;
	const cv::Mat whole = continuous(p_atlas); // a copy is never the published buffer
	if (gpu->gather(p_lookup, p_lookup->taps.data(), p_lookup->size, whole, p_published && whole.data == p_atlas.data, r_faces, &error)) {
		gpu_problem.clear();
		return true;
	}
	gpu_problem = "the coarse render on the CPU for the last map (on the device: " + error + ")";
	return false;
}

Cubemap CoarseCubemapRenderer::render(const cv::Mat &p_atlas_color, const glm::dvec3 &p_position, int p_size, const glm::dquat &p_room_from_world,
		bool p_atlas_published) const {
	if (p_size <= 0 || p_atlas_color.type() != CV_32FC3 || p_atlas_color.cols != mesh.atlas_width || p_atlas_color.rows != mesh.atlas_height) {
		return Cubemap();
	}
	const std::shared_ptr<const Lookup> taps = lookup(p_position, p_size, p_room_from_world);
	Cubemap cubemap;
	cubemap.size = p_size;
	for (int f = 0; f < 6; f++) {
		cubemap.faces[size_t(f)].create(p_size, p_size, CV_32FC3); // every texel is gathered below
		// A copy: the lookup is shared between maps, and the dense pass writes into the distances.
		cubemap.distance_m[size_t(f)] =
				cv::Mat(p_size, p_size, CV_32FC1, const_cast<float *>(taps->distance_m.data()) + size_t(f) * size_t(p_size) * size_t(p_size)).clone();
	}
	if (!gather_on_gpu(taps, p_atlas_color, p_atlas_published, &cubemap.faces)) {
		gather_faces<3>(*taps, p_atlas_color, &cubemap.faces);
	}
	return cubemap;
}

std::array<cv::Mat, 6> CoarseCubemapRenderer::render_channel(const cv::Mat &p_atlas, const glm::dvec3 &p_position, int p_size,
		const glm::dquat &p_room_from_world, bool p_atlas_published) const {
	std::array<cv::Mat, 6> faces;
	if (p_size <= 0 || p_atlas.type() != CV_32FC1 || p_atlas.cols != mesh.atlas_width || p_atlas.rows != mesh.atlas_height) {
		return faces;
	}
	for (cv::Mat &face : faces) {
		face.create(p_size, p_size, CV_32FC1);
	}
	const std::shared_ptr<const Lookup> taps = lookup(p_position, p_size, p_room_from_world);
	if (!gather_on_gpu(taps, p_atlas, p_atlas_published, &faces)) {
		gather_faces<1>(*taps, p_atlas, &faces);
	}
	return faces;
}

} // namespace roomprobe
