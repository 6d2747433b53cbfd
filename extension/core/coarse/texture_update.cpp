#include "texture_update.h"

#include <camera/omni_camera.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

namespace roomprobe {

namespace {

// Each tile's bounding sphere (about its surface points' box centre) and its one chart.
void make_tiles(TexelGeometry *io_geometry) {
	TexelGeometry &g = *io_geometry;
	const int size = TexelGeometry::tile_size;
	g.tiles_x = (g.width + size - 1) / size;
	g.tiles_y = (g.height + size - 1) / size;
	const size_t n = size_t(g.tiles_x) * g.tiles_y;
	g.tile_centres.assign(n, glm::dvec3(0.0));
	g.tile_radii.assign(n, -1.0);
	g.tile_charts.assign(n, -1);
	g.tile_normals.assign(n, glm::dvec3(0.0));
	for (int ty = 0; ty < g.tiles_y; ++ty) {
		for (int tx = 0; tx < g.tiles_x; ++tx) {
			const int x0 = tx * size, y0 = ty * size, x1 = std::min(x0 + size, g.width), y1 = std::min(y0 + size, g.height);
			glm::dvec3 low(std::numeric_limits<double>::max()), high(-std::numeric_limits<double>::max());
			int chart = -1, first_x = 0, first_y = 0;
			bool one_chart = true, any = false;
			for (int y = y0; y < y1; ++y) {
				for (int x = x0; x < x1; ++x) {
					const size_t i = size_t(y) * g.width + x;
					if (g.charts[i] < 0) {
						continue;
					}
					one_chart = one_chart && (!any || g.charts[i] == chart);
					if (!any) {
						first_x = x;
						first_y = y;
					}
					chart = g.charts[i];
					any = true;
					low = glm::min(low, g.points[i]);
					high = glm::max(high, g.points[i]);
				}
			}
			if (!any) {
				continue;
			}
			const size_t t = size_t(ty) * g.tiles_x + tx;
			const glm::dvec3 centre = 0.5 * (low + high);
			double radius2 = 0.0;
			for (int y = y0; y < y1; ++y) {
				for (int x = x0; x < x1; ++x) {
					const size_t i = size_t(y) * g.width + x;
					if (g.charts[i] >= 0) {
						const glm::dvec3 d = g.points[i] - centre;
						radius2 = std::max(radius2, glm::dot(d, d));
					}
				}
			}
			g.tile_centres[t] = centre;
			g.tile_radii[t] = std::sqrt(radius2);
			g.tile_charts[t] = one_chart ? chart : -1;
			g.tile_normals[t] = g.normals[size_t(first_y) * g.width + first_x];
		}
	}
}

} // namespace

TexelGeometry make_texel_geometry(const RoomMesh &p_mesh) {
	TexelGeometry g;
	g.width = std::max(p_mesh.atlas_width, 0);
	g.height = std::max(p_mesh.atlas_height, 0);
	const size_t n = size_t(g.width) * size_t(g.height);
	g.points.assign(n, glm::dvec3(0.0));
	g.normals.assign(n, glm::dvec3(0.0));
	g.charts.assign(n, -1);
	std::atomic<size_t> count { 0 };
	tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int> &p_rows) {
		size_t local = 0;
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			for (int x = 0; x < g.width; ++x) {
				Vec3 point, normal;
				if (!texel_to_world(p_mesh, x, y, &point, &normal)) {
					continue;
				}
				const size_t i = size_t(y) * g.width + x;
				g.points[i] = glm::dvec3(point.x, point.y, point.z);
				g.normals[i] = glm::dvec3(normal.x, normal.y, normal.z);
				g.charts[i] = find_chart_at_texel(p_mesh, x, y);
				++local;
			}
		}
		count += local;
	});
	g.surface_texels = count;
	make_tiles(&g);
	return g;
}

double observation_quality(double p_cos_view, double p_distance_m, double p_radius_fraction, const TextureUpdateOptions &p_options) {
	if (!(p_cos_view >= p_options.min_cos_view) || !(p_cos_view > 0.0)) {
		return 0.0;
	}
	const double d = std::max(p_distance_m, p_options.min_distance_m);
	const double r = std::clamp(p_radius_fraction, 0.0, 1.0);
	return p_cos_view / (d * d) * std::max(1.0 - p_options.edge_penalty * r * r, 0.0);
}

namespace {

// floor() as an int: a truncation where it is the same (x86-64's baseline has no rounding
// instruction, and floor() is a call there).
int floor_int(double p_value) {
	return p_value >= 0.0 ? static_cast<int>(p_value) : static_cast<int>(std::floor(p_value));
}

// Bilinear sample at p_pixel (pixel centres at integers), as linear R, G, B. Plain floats per
// channel (cv::Vec3f's operators saturate each element, a cost here).
template <typename T, int C>
cv::Vec3f bilinear(const cv::Mat &p_image, double p_x, double p_y, float p_scale) {
	const int x0 = floor_int(p_x);
	const int y0 = floor_int(p_y);
	const float fx = static_cast<float>(p_x - x0);
	const float fy = static_cast<float>(p_y - y0);
	const int x1 = std::min(x0 + 1, p_image.cols - 1);
	const int y1 = std::min(y0 + 1, p_image.rows - 1);
	const int xa = std::max(x0, 0), ya = std::max(y0, 0);
	const T *top_row = p_image.ptr<T>(ya), *bottom_row = p_image.ptr<T>(y1);
	const T *a = top_row + size_t(xa) * C, *b = top_row + size_t(x1) * C;
	const T *c = bottom_row + size_t(xa) * C, *d = bottom_row + size_t(x1) * C;
	cv::Vec3f out;
	for (int k = 0; k < 3; k++) {
		const int e = C == 1 ? 0 : k;
		const float top = static_cast<float>(a[e]) * (1.0f - fx) + static_cast<float>(b[e]) * fx;
		const float bottom = static_cast<float>(c[e]) * (1.0f - fx) + static_cast<float>(d[e]) * fx;
		out[k] = (top * (1.0f - fy) + bottom * fy) * p_scale;
	}
	return out;
}

// The fisheye image's sample at a pixel, as linear R, G, B (8-bit images scaled to [0, 1]).
cv::Vec3f sample_image(const cv::Mat &p_image, const glm::dvec2 &p_pixel) {
	switch (p_image.type()) {
		case CV_8UC1:
			return bilinear<uint8_t, 1>(p_image, p_pixel.x, p_pixel.y, 1.0f / 255.0f);
		case CV_8UC3:
			return bilinear<uint8_t, 3>(p_image, p_pixel.x, p_pixel.y, 1.0f / 255.0f);
		default:
			return bilinear<float, 3>(p_image, p_pixel.x, p_pixel.y, 1.0f);
	}
}

// A clipped sample this much brighter than the unclipped value kept proves that value wrong: its
// radiance is at least the sample's (a margin over 1 for the noise of the two linearisations).
constexpr float CONTRADICTION = 1.25f;

// Whether any of the four pixels a bilinear sample at p_pixel reads is clipped (p_saturated:
// CV_8UC1, 255 where clipped).
bool sample_saturated(const cv::Mat &p_saturated, const glm::dvec2 &p_pixel) {
	const int x0 = std::max(floor_int(p_pixel.x), 0), y0 = std::max(floor_int(p_pixel.y), 0);
	const int x1 = std::min(x0 + 1, p_saturated.cols - 1), y1 = std::min(y0 + 1, p_saturated.rows - 1);
	const uint8_t *top = p_saturated.ptr<uint8_t>(std::min(y0, p_saturated.rows - 1)), *bottom = p_saturated.ptr<uint8_t>(y1);
	const int xa = std::min(x0, p_saturated.cols - 1);
	return (top[xa] | top[x1] | bottom[xa] | bottom[x1]) != 0;
}

// One frame's fisheye, as the per-texel visibility test needs it.
struct FisheyeView {
	const OmniParams *params = nullptr;
	glm::dmat3 rotation = glm::dmat3(1.0); // fisheye from world
	glm::dvec3 translation = glm::dvec3(0.0);
	glm::dvec3 camera = glm::dvec3(0.0); // the fisheye's centre, world
	int cols = 0, rows = 0;
	double margin = 0.0; // rim_margin_px
	bool has_circle = false;
	double circle_cx = 0.0, circle_cy = 0.0, radius = 0.0;
	double max_x = 0.0, max_y = 0.0; // the last pixel centres the rim margin leaves
	double rim2 = 0.0; // (radius - margin)^2; -1 when nothing is inside

	glm::dvec3 to_camera(const glm::dvec3 &p_world) const { return rotation * p_world + translation; }
};

FisheyeView fisheye_view(const OmniParams &p_params, const Pose &p_world_from_fisheye, int p_cols, int p_rows, const TextureUpdateOptions &p_options) {
	FisheyeView view;
	const Pose fisheye_from_world = inverse(p_world_from_fisheye);
	view.params = &p_params;
	view.rotation = glm::mat3_cast(fisheye_from_world.rotation);
	view.translation = fisheye_from_world.translation;
	view.camera = p_world_from_fisheye.translation;
	view.cols = p_cols;
	view.rows = p_rows;
	view.margin = p_options.rim_margin_px;
	view.has_circle = p_params.circle_radius > 0.0;
	view.circle_cx = view.has_circle ? p_params.circle_cx : 0.5 * (view.cols - 1);
	view.circle_cy = view.has_circle ? p_params.circle_cy : 0.5 * (view.rows - 1);
	view.radius = view.has_circle ? p_params.circle_radius : 0.5 * std::hypot(double(view.cols), double(view.rows));
	view.max_x = view.cols - 1 - view.margin;
	view.max_y = view.rows - 1 - view.margin;
	const double rim = view.radius - view.margin;
	view.rim2 = rim < 0.0 ? -1.0 : rim * rim;
	return view;
}

// Where texels land in the image: projected on the spot (the plain path), or read from the
// frame's TexelProjection, where a texel's neighbour one chart axis step away is the next texel
// along atlas x (u) or y (v) on the same chart.
class TexelPixels {
public:
	TexelPixels(const FisheyeView &p_view, const TexelGeometry &p_geometry, const TexelProjection *p_projection) :
			view(p_view), geometry(p_geometry), projection(p_projection), projected(p_projection ? p_projection->pixels.ptr<cv::Vec2d>(0) : nullptr) {}

	// Whether texels of tile column p_tx in tile row p_ty need looking at (all, projecting on the spot).
	bool tile_seen(int p_tx, int p_ty) const { return !projection || projection->tile_seen[size_t(p_ty) * geometry.tiles_x + p_tx] != 0; }

	bool pixel(size_t p_i, glm::dvec2 *r_pixel) const {
		if (projected) {
			const cv::Vec2d &p = projected[p_i];
			*r_pixel = glm::dvec2(p[0], p[1]);
			return !std::isnan(p[0]);
		}
		return project_omni(*view.params, view.to_camera(geometry.points[p_i]), r_pixel);
	}

	// The pixel of texel (p_x, p_y)'s point plus one step along its chart's u axis (p_dx = 1) or
	// v axis (p_dy = 1).
	bool step_pixel(int p_x, int p_y, int p_dx, int p_dy, const RoomMesh &p_mesh, glm::dvec2 *r_pixel) const {
		const size_t i = size_t(p_y) * geometry.width + p_x;
		const int x = p_x + p_dx, y = p_y + p_dy;
		if (projected && x < geometry.width && y < geometry.height && projection->seen(geometry, x, y)) {
			const size_t j = size_t(y) * geometry.width + x;
			if (geometry.charts[j] == geometry.charts[i]) {
				return pixel(j, r_pixel);
			}
		}
		const Chart &chart = p_mesh.charts[geometry.charts[i]];
		const Vec3 &step = p_dx ? chart.u_axis_m : chart.v_axis_m;
		return project_omni(*view.params, view.to_camera(geometry.points[i] + glm::dvec3(step.x, step.y, step.z)), r_pixel);
	}

	// Whether texel i is seen this frame: false for the back of the surface, outside the image or
	// the image circle's rim. r_r2: the squared distance of its pixel from the circle centre.
	bool observe(size_t p_i, glm::dvec2 *r_pixel, double *r_cos_view, double *r_distance, double *r_r2) const {
		if (projected && std::isnan(projected[p_i][0])) {
			return false; // the cheapest test first
		}
		const glm::dvec3 &point = geometry.points[p_i];
		const glm::dvec3 to_camera = view.camera - point;
		const double distance = glm::length(to_camera);
		if (!(distance > 1e-9)) {
			return false;
		}
		const double cos_view = glm::dot(geometry.normals[p_i], to_camera) / distance;
		if (cos_view <= 0.0) {
			return false; // the back of the surface
		}
		glm::dvec2 pixel;
		if (!this->pixel(p_i, &pixel)) {
			return false;
		}
		const double margin = view.margin;
		if (!(pixel.x >= margin && pixel.y >= margin && pixel.x <= view.max_x && pixel.y <= view.max_y)) {
			return false;
		}
		const double dx = pixel.x - view.circle_cx, dy = pixel.y - view.circle_cy;
		const double r2 = dx * dx + dy * dy;
		if (view.has_circle && !(r2 <= view.rim2)) {
			return false;
		}
		*r_pixel = pixel;
		*r_cos_view = cos_view;
		*r_distance = distance;
		*r_r2 = r2;
		return true;
	}

private:
	const FisheyeView &view;
	const TexelGeometry &geometry;
	const TexelProjection *projection; // null: project on the spot
	const cv::Vec2d *projected; // its pixels
};

// The first x on p_step's grid in the tile after x's.
int next_tile_x(int p_x, int p_step) {
	const int next = (p_x / TexelGeometry::tile_size + 1) * TexelGeometry::tile_size;
	return (next + p_step - 1) / p_step * p_step;
}

bool valid_image_type(const cv::Mat &p_image) {
	const int type = p_image.type();
	return !p_image.empty() && (type == CV_8UC1 || type == CV_8UC3 || type == CV_32FC3);
}

bool projection_fits(const TexelGeometry &p_geometry, const TexelProjection *p_projection) {
	return !p_projection || (p_projection->pixels.type() == CV_64FC2 && p_projection->pixels.isContinuous() &&
									p_projection->pixels.size() == cv::Size(p_geometry.width, p_geometry.height) &&
									p_projection->tile_seen.size() == size_t(p_geometry.tiles_x) * p_geometry.tiles_y);
}

// 1 - edge_penalty * r^2 (r the radius fraction, at most 1), at least 0.
double edge_factor(double p_radius_fraction2, const TextureUpdateOptions &p_options) {
	return std::max(1.0 - p_options.edge_penalty * std::clamp(p_radius_fraction2, 0.0, 1.0), 0.0);
}

void sample_texels(const TexelGeometry &p_geometry, const TexelProjection *p_projection, const OmniParams &p_params, const Pose &p_world_from_fisheye,
		const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, const cv::Mat &p_only, int p_step, const TextureUpdateOptions &p_options,
		cv::Mat *r_samples, cv::Mat *r_visible) {
	const int w = p_geometry.width, h = p_geometry.height;
	r_samples->create(h, w, CV_32FC3);
	r_visible->create(h, w, CV_8UC1);
	r_visible->setTo(cv::Scalar::all(0));
	if (!valid_image_type(p_fisheye_image) || p_only.size() != cv::Size(w, h) || p_only.type() != CV_8UC1 || !projection_fits(p_geometry, p_projection) ||
			(p_visibility_mask && (p_visibility_mask->size() != cv::Size(w, h) || p_visibility_mask->type() != CV_8UC1))) {
		return;
	}
	const FisheyeView view = fisheye_view(p_params, p_world_from_fisheye, p_fisheye_image.cols, p_fisheye_image.rows, p_options);
	const TexelPixels pixels(view, p_geometry, p_projection);
	const int step = std::max(1, p_step);
	tbb::parallel_for(tbb::blocked_range<int>(0, (h + step - 1) / step), [&](const tbb::blocked_range<int> &p_rows) {
		for (int row = p_rows.begin(); row < p_rows.end(); ++row) {
			const int y = row * step;
			const uint8_t *only_row = p_only.ptr<uint8_t>(y);
			const uint8_t *mask_row = p_visibility_mask ? p_visibility_mask->ptr<uint8_t>(y) : nullptr;
			cv::Vec3f *sample_row = r_samples->ptr<cv::Vec3f>(y);
			uint8_t *visible_row = r_visible->ptr<uint8_t>(y);
			for (int x = 0; x < w; x += step) {
				if (x % TexelGeometry::tile_size < step && !pixels.tile_seen(x / TexelGeometry::tile_size, y / TexelGeometry::tile_size)) {
					x = next_tile_x(x, step) - step; // the tile is not seen: on to the next one
					continue;
				}
				const size_t i = size_t(y) * w + x;
				glm::dvec2 pixel;
				double cos_view, distance, r2;
				if (only_row[x] == 0 || p_geometry.charts[i] < 0 || (mask_row && mask_row[x] == 0) || !pixels.observe(i, &pixel, &cos_view, &distance, &r2)) {
					continue;
				}
				sample_row[x] = sample_image(p_fisheye_image, pixel);
				visible_row[x] = 255;
			}
		}
	});
}

TextureUpdateStats update_texture(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const TexelProjection *p_projection, const OmniParams &p_params,
		const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, CoarseTexture *io_texture,
		const TextureUpdateOptions &p_options, LightingPairs *r_pairs, const cv::Mat *p_saturated) {
	TextureUpdateStats stats;
	const auto start = std::chrono::steady_clock::now();
	const int w = p_mesh.atlas_width, h = p_mesh.atlas_height;
	if (!io_texture || p_geometry.width != w || p_geometry.height != h || p_fisheye_image.empty() || !projection_fits(p_geometry, p_projection)) {
		return stats;
	}
	if (!valid_image_type(p_fisheye_image)) {
		return stats;
	}
	CoarseTexture &tex = *io_texture;
	if (tex.color.size() != cv::Size(w, h) || tex.color.type() != CV_32FC3 || tex.observed.size() != cv::Size(w, h) ||
			tex.quality.size() != cv::Size(w, h) || tex.updated.size() != cv::Size(w, h)) {
		return stats;
	}
	if (p_visibility_mask && (p_visibility_mask->size() != cv::Size(w, h) || p_visibility_mask->type() != CV_8UC1)) {
		return stats;
	}
	if (p_saturated && (p_saturated->empty() || p_saturated->size() != p_fisheye_image.size() || p_saturated->type() != CV_8UC1)) {
		p_saturated = nullptr; // no mask of this frame: nothing is known to be clipped
	}
	if (tex.saturated.size() != cv::Size(w, h) || tex.saturated.type() != CV_8UC1) {
		tex.saturated = cv::Mat(h, w, CV_8UC1, cv::Scalar(0)); // a texture from before the mask existed
	}

	const FisheyeView view = fisheye_view(p_params, p_world_from_fisheye, p_fisheye_image.cols, p_fisheye_image.rows, p_options);
	const TexelPixels pixels(view, p_geometry, p_projection);
	const double radius2 = view.radius * view.radius;
	const bool best = p_options.policy == TextureUpdatePolicy::Best;
	const double keep_fraction = 1.0 - std::clamp(p_options.replace_epsilon, 0.0, 1.0);

	const int pair_step = r_pairs ? r_pairs->begin(h) : 1;
	std::atomic<size_t> visible_total { 0 }, updated_total { 0 };
	tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int> &p_rows) {
		size_t visible = 0, updated = 0;
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			std::vector<LightingSample> *pairs_row = r_pairs && y % pair_step == 0 ? &r_pairs->rows[size_t(y / pair_step)] : nullptr;
			uint8_t *updated_row = tex.updated.ptr<uint8_t>(y);
			std::fill(updated_row, updated_row + w, uint8_t(0));
			const uint8_t *mask_row = p_visibility_mask ? p_visibility_mask->ptr<uint8_t>(y) : nullptr;
			cv::Vec3f *color_row = tex.color.ptr<cv::Vec3f>(y);
			float *quality_row = tex.quality.ptr<float>(y);
			uint8_t *observed_row = tex.observed.ptr<uint8_t>(y);
			uint8_t *saturated_row = tex.saturated.ptr<uint8_t>(y);
			for (int x = 0; x < w; ++x) {
				if (x % TexelGeometry::tile_size == 0 && !pixels.tile_seen(x / TexelGeometry::tile_size, y / TexelGeometry::tile_size)) {
					x += TexelGeometry::tile_size - 1; // the tile is not seen
					continue;
				}
				const size_t i = size_t(y) * w + x;
				if (p_geometry.charts[i] < 0 || (mask_row && mask_row[x] == 0)) {
					continue;
				}
				glm::dvec2 pixel;
				double cos_view, distance, r2;
				if (!pixels.observe(i, &pixel, &cos_view, &distance, &r2)) {
					continue;
				}
				++visible;
				const bool clipped = p_saturated && sample_saturated(*p_saturated, pixel);
				cv::Vec3f sample;
				bool sampled = false;
				if (pairs_row && x % pair_step == 0 && observed_row[x] != 0 && quality_row[x] > 0.0f && !clipped && saturated_row[x] == 0) {
					// Observed by the fisheye before (this texel's own write comes below; an RGB
					// camera's value, quality 0, is another camera's), neither value clipped: a
					// lighting pair.
					sample = sample_image(p_fisheye_image, pixel);
					sampled = true;
					const glm::dvec3 &at = p_geometry.points[i];
					pairs_row->push_back({ color_row[x], sample, cv::Vec3f(float(at.x), float(at.y), float(at.z)) });
				}
				const double edge = edge_factor(r2 / radius2, p_options);
				double quality = 0.0;
				glm::dvec2 pu, pv;
				if (!(cos_view >= p_options.min_cos_view)) {
					// Too oblique: never updated (observation_quality's 0).
				} else if (p_options.footprint_quality && edge > 0.0 && pixels.step_pixel(x, y, 1, 0, p_mesh, &pu) &&
						pixels.step_pixel(x, y, 0, 1, p_mesh, &pv)) {
					// The texel's area in the image, pixels^2, from the pixels of its two edges.
					const glm::dvec2 du = pu - pixel, dv = pv - pixel;
					quality = std::abs(du.x * dv.y - du.y * dv.x) * edge;
				} else {
					// (Where an edge's projection fails, at the model's limit, the closed form stays.)
					quality = observation_quality(cos_view, distance, 0.0, p_options) * edge;
				}
				if (best && quality <= 0.0) {
					continue;
				}
				// HDR (rig/photometry.h): a clipped value is only a lower bound of the radiance. It
				// never replaces an unclipped one, unless the bound itself proves that one wrong (the
				// scene changed: a light switched on is clipped at the long exposure first); an
				// unclipped one always replaces it; between two clipped ones the brighter bound (a
				// shorter exposure's) wins.
				const bool kept_clipped = observed_row[x] && saturated_row[x] != 0;
				if (!sampled) {
					sample = sample_image(p_fisheye_image, pixel);
				}
				const float kept_sum = color_row[x][0] + color_row[x][1] + color_row[x][2];
				if (observed_row[x] && clipped && !kept_clipped && !(sample[0] + sample[1] + sample[2] > CONTRADICTION * kept_sum)) {
					continue;
				}
				bool reset_quality = false;
				if (kept_clipped && !clipped) {
					reset_quality = true;
				} else if (clipped && !kept_clipped) {
					reset_quality = true; // contradicted above
				} else if (kept_clipped && clipped) {
					if (!(sample[0] + sample[1] + sample[2] > kept_sum)) {
						continue;
					}
				} else if (best && observed_row[x] && quality < quality_row[x] * keep_fraction) {
					continue;
				}
				color_row[x] = sample;
				saturated_row[x] = clipped ? 255 : 0;
				// Best: the best quality ever seen, not the new (possibly epsilon-worse) one's, so that
				// a run of slightly worse views cannot ratchet the reference down (measured: with the
				// new one's, epsilon = 0.1 came out worse than the "last" policy).
				quality_row[x] = static_cast<float>(best && observed_row[x] && !reset_quality ? std::max(double(quality_row[x]), quality) : quality);
				observed_row[x] = 255;
				updated_row[x] = 255;
				++updated;
			}
		}
		visible_total += visible;
		updated_total += updated;
	});
	stats.texels_visible = visible_total;
	stats.texels_updated = updated_total;
	stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	return stats;
}

} // namespace

namespace {

// cos of the half angle of the cone the lens sees within: the widest ray of its image circle's rim
// (or, without a circle, of the image's border), sampled densely, with a degree to spare for the
// rays between the samples. -2 (no cone) where a rim pixel has no ray.
double lens_cone_cos(const OmniParams &p_params) {
	const int samples = 720;
	const bool circle = p_params.circle_radius > 0.0;
	double widest = 1.0; // the smallest cos seen
	for (int k = 0; k < samples; ++k) {
		glm::dvec2 pixel;
		const double t = double(k) / samples;
		if (circle) {
			const double angle = 2.0 * std::numbers::pi * t;
			pixel = glm::dvec2(p_params.circle_cx, p_params.circle_cy) + p_params.circle_radius * glm::dvec2(std::cos(angle), std::sin(angle));
		} else {
			// The border's four sides in turn, pixel centres' outer edges at -0.5 and size - 0.5.
			const double w = p_params.width, h = p_params.height, along = 4.0 * t - std::floor(4.0 * t);
			const int side = int(4.0 * t);
			pixel = side == 0 ? glm::dvec2(-0.5 + along * w, -0.5)
					: side == 1 ? glm::dvec2(w - 0.5, -0.5 + along * h)
					: side == 2 ? glm::dvec2(w - 0.5 - along * w, h - 0.5)
								: glm::dvec2(-0.5, h - 0.5 - along * h);
		}
		glm::dvec3 ray;
		if (!unproject_omni(p_params, pixel, &ray)) {
			widest = -2.0; // a rim pixel without a ray: the rim bounds nothing
			break;
		}
		widest = std::min(widest, ray.z);
	}
	// project_omni sees nothing beyond max_angle_deg either.
	const double limit = p_params.max_angle_deg > 0.0 ? p_params.max_angle_deg * std::numbers::pi / 180.0 : std::numbers::pi;
	const double rim = widest < -1.0 ? std::numbers::pi : std::acos(std::clamp(widest, -1.0, 1.0)) + std::numbers::pi / 180.0;
	const double half_angle = std::min(rim, limit);
	return half_angle >= std::numbers::pi ? -2.0 : std::cos(half_angle);
}

bool same_lens(const OmniParams &p_a, const OmniParams &p_b) {
	return p_a.width == p_b.width && p_a.height == p_b.height && p_a.xi == p_b.xi && p_a.fx == p_b.fx && p_a.fy == p_b.fy && p_a.cx == p_b.cx &&
			p_a.cy == p_b.cy && p_a.skew == p_b.skew && p_a.k1 == p_b.k1 && p_a.k2 == p_b.k2 && p_a.p1 == p_b.p1 && p_a.p2 == p_b.p2 &&
			p_a.circle_cx == p_b.circle_cx && p_a.circle_cy == p_b.circle_cy && p_a.circle_radius == p_b.circle_radius &&
			p_a.max_angle_deg == p_b.max_angle_deg;
}

// Whether any point of tile t can be seen: in front of its one chart's plane, and its bounding
// sphere reaching into the lens's cone.
bool tile_may_be_seen(const TexelGeometry &p_geometry, size_t p_t, const FisheyeView &p_view, double p_cone_cos) {
	const double radius = p_geometry.tile_radii[p_t];
	if (radius < 0.0) {
		return false; // no surface texel
	}
	const glm::dvec3 &centre = p_geometry.tile_centres[p_t];
	// One chart, one plane: the camera behind it sees none of the tile (every point p lies within
	// radius of the centre, so n . (camera - p) <= n . (camera - centre) + radius).
	if (p_geometry.tile_charts[p_t] >= 0 && glm::dot(p_geometry.tile_normals[p_t], p_view.camera - centre) + radius <= 0.0) {
		return false;
	}
	if (p_cone_cos < -1.0) {
		return true;
	}
	const glm::dvec3 d = p_view.to_camera(centre);
	const double distance = glm::length(d);
	if (distance <= radius) {
		return true;
	}
	// Outside when the angle from the axis exceeds the half angle plus the sphere's angular radius.
	const double half_angle = std::acos(p_cone_cos), reach = std::asin(radius / distance);
	const double angle = std::acos(std::clamp(d.z / distance, -1.0, 1.0));
	return angle <= half_angle + reach;
}

} // namespace

void project_texels(const TexelGeometry &p_geometry, const OmniParams &p_params, const Pose &p_world_from_fisheye, TexelProjection *io_projection) {
	const int w = p_geometry.width, h = p_geometry.height;
	TexelProjection &projection = *io_projection;
	projection.pixels.create(h, w, CV_64FC2);
	if (projection.cone_cos == -2.0 || !same_lens(projection.cone_lens, p_params)) {
		projection.cone_lens = p_params;
		projection.cone_cos = lens_cone_cos(p_params);
	}
	const FisheyeView view = fisheye_view(p_params, p_world_from_fisheye, p_params.width, p_params.height, TextureUpdateOptions());
	projection.tile_seen.resize(size_t(p_geometry.tiles_x) * p_geometry.tiles_y);
	for (size_t t = 0; t < projection.tile_seen.size(); ++t) {
		projection.tile_seen[t] = tile_may_be_seen(p_geometry, t, view, projection.cone_cos) ? 1 : 0;
	}
	const double nan = std::numeric_limits<double>::quiet_NaN();
	const int size = TexelGeometry::tile_size;
	tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int> &p_rows) {
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			cv::Vec2d *row = projection.pixels.ptr<cv::Vec2d>(y);
			const uint8_t *seen_row = projection.tile_seen.data() + size_t(y / size) * p_geometry.tiles_x;
			for (int tx = 0; tx < p_geometry.tiles_x; ++tx) {
				if (!seen_row[tx]) {
					continue;
				}
				for (int x = tx * size; x < std::min(w, tx * size + size); ++x) {
					const size_t i = size_t(y) * w + x;
					glm::dvec2 pixel;
					if (p_geometry.charts[i] >= 0 && project_omni(p_params, view.to_camera(p_geometry.points[i]), &pixel)) {
						row[x] = cv::Vec2d(pixel.x, pixel.y);
					} else {
						row[x] = cv::Vec2d(nan, nan);
					}
				}
			}
		}
	});
}

void sample_coarse_texels(const TexelGeometry &p_geometry, const OmniParams &p_params, const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image,
		const cv::Mat *p_visibility_mask, const cv::Mat &p_only, int p_step, const TextureUpdateOptions &p_options, cv::Mat *r_samples, cv::Mat *r_visible) {
	sample_texels(p_geometry, nullptr, p_params, p_world_from_fisheye, p_fisheye_image, p_visibility_mask, p_only, p_step, p_options, r_samples, r_visible);
}

void sample_coarse_texels(const TexelGeometry &p_geometry, const TexelProjection &p_projection, const OmniParams &p_params, const Pose &p_world_from_fisheye,
		const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, const cv::Mat &p_only, int p_step, const TextureUpdateOptions &p_options,
		cv::Mat *r_samples, cv::Mat *r_visible) {
	sample_texels(p_geometry, &p_projection, p_params, p_world_from_fisheye, p_fisheye_image, p_visibility_mask, p_only, p_step, p_options, r_samples, r_visible);
}

TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const OmniParams &p_params,
		const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask,
		CoarseTexture *io_texture, const TextureUpdateOptions &p_options) {
	return update_texture(p_mesh, p_geometry, nullptr, p_params, p_world_from_fisheye, p_fisheye_image, p_visibility_mask, io_texture, p_options, nullptr, nullptr);
}

TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const TexelProjection &p_projection, const OmniParams &p_params,
		const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, CoarseTexture *io_texture,
		const TextureUpdateOptions &p_options, LightingPairs *r_pairs, const cv::Mat *p_saturated) {
	return update_texture(p_mesh, p_geometry, &p_projection, p_params, p_world_from_fisheye, p_fisheye_image, p_visibility_mask, io_texture, p_options, r_pairs,
			p_saturated);
}

int LightingPairs::begin(int p_height) {
	const int pair_step = std::max(1, step);
	rows.resize(size_t((p_height + pair_step - 1) / pair_step));
	for (std::vector<LightingSample> &row : rows) {
		row.clear();
	}
	return pair_step;
}

const std::vector<LightingSample> &LightingPairs::gather() {
	size_t n = 0;
	for (const std::vector<LightingSample> &row : rows) {
		n += row.size();
	}
	all.clear();
	all.reserve(n);
	for (const std::vector<LightingSample> &row : rows) {
		all.insert(all.end(), row.begin(), row.end());
	}
	return all;
}

TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const OmniParams &p_params, const Pose &p_world_from_fisheye,
		const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, CoarseTexture *io_texture,
		const TextureUpdateOptions &p_options) {
	const auto start = std::chrono::steady_clock::now();
	const TexelGeometry geometry = make_texel_geometry(p_mesh);
	TextureUpdateStats stats = update_coarse_texture(p_mesh, geometry, p_params, p_world_from_fisheye, p_fisheye_image,
			p_visibility_mask, io_texture, p_options);
	stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	return stats;
}

} // namespace roomprobe
