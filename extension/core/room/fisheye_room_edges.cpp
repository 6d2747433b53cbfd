// Step 3 of room_estimation.h, and the walls the RGB-D camera never saw: the room's top edges
// (where the walls meet the ceiling) as the upward fisheye sees them.
#include "room_estimation.h"

#include "wall_planes.h"

#include <camera/omni_camera.h>

#include <glm/geometric.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace roomprobe {

using namespace room_planes;

namespace {

constexpr double STEP_M = 0.01; // the heights and offsets searched
constexpr double SAMPLE_SPACING_M = 0.05; // points along an edge
constexpr double CORNER_CLEARANCE_M = 0.15; // kept clear of the corners (other walls' edges meet there)
constexpr double MIN_CONTRAST = 1.5; // a ceiling edge stands this far above the median of the heights searched
// A wall found beyond where the view ended stands this many robust standard deviations above
// the median of the positions searched (the 5-sigma of a detection). Measured against the
// profile's own scatter, not its level: the positions behind the true wall see its texture, which
// lifts the median and the scatter alike. Seen, tracked 10-s sweeps of two_rooms: true walls 8.4
// (the right room's end, room sweep) and 9.4 (the wardrobe's side, orbit), a false one (the room
// beyond a partition the orbit never passed) 3.3; as ratios to the median 5.4, 9.9 and 2.5, too
// close to one threshold.
constexpr double MIN_WALL_SIGMAS = 5.0;

// A float image for edge measurements: log luminance, so that edges between surfaces of
// different brightness weigh alike in dark and bright parts (8-bit and HDR frames alike).
cv::Mat edge_image(const cv::Mat &p_image) {
	cv::Mat gray;
	if (p_image.channels() == 3) {
		cv::cvtColor(p_image, gray, cv::COLOR_RGB2GRAY);
	} else {
		gray = p_image;
	}
	const double scale = gray.depth() == CV_8U ? 1.0 / 255.0 : 1.0;
	gray.convertTo(gray, CV_32F, scale);
	cv::max(gray, 1.0 / 255.0, gray);
	cv::log(gray, gray);
	cv::GaussianBlur(gray, gray, cv::Size(0, 0), 1.0);
	return gray;
}

float bilinear(const cv::Mat &p_image, const glm::dvec2 &p_pixel) {
	const int x = int(std::floor(p_pixel.x)), y = int(std::floor(p_pixel.y));
	if (x < 0 || y < 0 || x + 1 >= p_image.cols || y + 1 >= p_image.rows) {
		return 0.0f;
	}
	const float fx = float(p_pixel.x - x), fy = float(p_pixel.y - y);
	const float *row0 = p_image.ptr<float>(y), *row1 = p_image.ptr<float>(y + 1);
	return (1 - fy) * ((1 - fx) * row0[x] + fx * row0[x + 1]) + fy * ((1 - fx) * row1[x] + fx * row1[x + 1]);
}

double median_of(std::vector<double> p_values) {
	if (p_values.empty()) {
		return 0.0;
	}
	std::nth_element(p_values.begin(), p_values.begin() + long(p_values.size() / 2), p_values.end());
	return p_values[p_values.size() / 2];
}

// Whether the segments p-q and a-b cross at a point inside both (touching does not count).
bool segments_cross(const Vec2 &p_p, const Vec2 &p_q, const Vec2 &p_a, const Vec2 &p_b) {
	const auto side = [](const Vec2 &o, const Vec2 &u, const Vec2 &v) { return (u.x - o.x) * (v.y - o.y) - (u.y - o.y) * (v.x - o.x); };
	const double d1 = side(p_a, p_b, p_p), d2 = side(p_a, p_b, p_q), d3 = side(p_p, p_q, p_a), d4 = side(p_p, p_q, p_b);
	return ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0));
}

struct EdgeViews {
	struct View {
		cv::Mat gray, gx, gy; // log luminance, blurred, and its gradient
		cv::Mat detail; // gray less its local mean: the lens's vignetting and the exposure cancel
		Pose fisheye_from_world;
		Vec2 floor_position; // the fisheye's centre on the floorplan
	};
	std::vector<View> views;
	const OmniParams *fisheye = nullptr;
	// Walls known to stand floor to ceiling (edges seen as walls, less those being searched): a
	// point behind one from a view is not in that view, which shows the wall there instead (the
	// right room's edges from the left room, through the partition).
	std::vector<std::pair<Vec2, Vec2>> occluders;

	void set_occluders(const Floorplan &p_floorplan, const std::vector<double> &p_edge_confidence, size_t p_searched, size_t p_skip_neighbours) {
		occluders.clear();
		const size_t n = p_floorplan.points.size();
		for (size_t j = 0; j < n && j < p_edge_confidence.size(); j++) {
			const size_t distance = std::min((j + n - p_searched) % n, (p_searched + n - j) % n);
			if (p_edge_confidence[j] >= 0.3 && distance > p_skip_neighbours) {
				occluders.emplace_back(p_floorplan.points[j], p_floorplan.points[(j + 1) % n]);
			}
		}
	}

	bool hidden(const View &p_view, const glm::dvec3 &p_world) const {
		const Vec2 to = { p_world.x, p_world.z };
		for (const auto &[a, b] : occluders) {
			if (segments_cross(p_view.floor_position, to, a, b)) {
				return true;
			}
		}
		return false;
	}

	EdgeViews(const std::vector<FisheyeView> &p_views, const OmniParams &p_fisheye) : fisheye(&p_fisheye) {
		for (const FisheyeView &view : p_views) {
			if (view.image.empty() || view.image.cols != p_fisheye.width || view.image.rows != p_fisheye.height) {
				continue;
			}
			View v;
			v.gray = edge_image(view.image);
			cv::GaussianBlur(v.gray, v.detail, cv::Size(0, 0), 6.0);
			v.detail = v.gray - v.detail;
			cv::Sobel(v.gray, v.gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
			cv::Sobel(v.gray, v.gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
			v.fisheye_from_world = inverse(view.world_from_fisheye);
			v.floor_position = { view.world_from_fisheye.translation.x, view.world_from_fisheye.translation.z };
			views.push_back(std::move(v));
		}
	}

	// The image gradient along the world's vertical at p_world, averaged over the views that see
	// it; -1 when none does.
	double vertical_edge(const glm::dvec3 &p_world) const {
		double sum = 0.0;
		int seen = 0;
		for (const View &view : views) {
			glm::dvec2 at, above;
			if (hidden(view, p_world)) {
				continue;
			}
			const glm::dvec3 p = transform_point(view.fisheye_from_world, p_world);
			const glm::dvec3 q = transform_point(view.fisheye_from_world, p_world + glm::dvec3(0.0, 0.02, 0.0));
			if (!project_omni(*fisheye, p, &at) || !project_omni(*fisheye, q, &above) || !omni_pixel_valid(*fisheye, at)) {
				continue;
			}
			const glm::dvec2 direction = above - at;
			const double length = glm::length(direction);
			if (!(length > 1e-3)) {
				continue;
			}
			sum += std::abs((direction.x * bilinear(view.gx, at) + direction.y * bilinear(view.gy, at)) / length);
			seen++;
		}
		return seen > 0 ? sum / seen : -1.0;
	}

	// The median edge strength along the segment a-b at p_height_m (points clear of the corners);
	// -1 when too little of it is in view.
	double segment_edge(const Vec2 &p_a, const Vec2 &p_b, double p_height_m) const {
		const double length = std::hypot(p_b.x - p_a.x, p_b.y - p_a.y);
		std::vector<double> values;
		for (double t = CORNER_CLEARANCE_M; t <= length - CORNER_CLEARANCE_M; t += SAMPLE_SPACING_M) {
			const double v = vertical_edge(glm::dvec3(p_a.x + (p_b.x - p_a.x) * t / length, p_height_m, p_a.y + (p_b.y - p_a.y) * t / length));
			if (v >= 0.0) {
				values.push_back(v);
			}
		}
		return values.size() < 5 ? -1.0 : median_of(std::move(values));
	}

	double strip_spread(const Vec2 &p_a, const Vec2 &p_b, double p_height_m, const std::vector<glm::dvec3> &p_offsets) const;
};

// How differently the views see a strip beside the edge a-b lifted to p_height_m: the median
// over points (10 cm apart along it, each offset by one of p_offsets) of the spread across the
// views of log luminance less its local mean (vignetting and exposure differ between views). A strip on a real surface looks the same from every view; one
// in the air shows each view something else behind it (parallax). Just inside a wall's top
// edge (offsets along the ceiling), only the true ceiling height looks alike; just below it
// (offsets down the wall), only the true wall's position does. -1 when too few points are seen
// by three views.
double EdgeViews::strip_spread(const Vec2 &p_a, const Vec2 &p_b, double p_height_m, const std::vector<glm::dvec3> &p_offsets) const {
	const double length = std::hypot(p_b.x - p_a.x, p_b.y - p_a.y);
	std::vector<double> spreads;
	std::vector<double> values;
	for (double t = CORNER_CLEARANCE_M; t <= length - CORNER_CLEARANCE_M; t += 0.1) {
		const glm::dvec3 base(p_a.x + (p_b.x - p_a.x) * t / length, p_height_m, p_a.y + (p_b.y - p_a.y) * t / length);
		for (const glm::dvec3 &offset : p_offsets) {
			values.clear();
			for (const View &view : views) {
				glm::dvec2 at;
				if (!hidden(view, base + offset) && project_omni(*fisheye, transform_point(view.fisheye_from_world, base + offset), &at) && omni_pixel_valid(*fisheye, at)) {
					values.push_back(bilinear(view.detail, at));
				}
			}
			if (values.size() < 3) {
				continue;
			}
			double mean = 0.0, squares = 0.0;
			for (const double v : values) {
				mean += v;
			}
			mean /= double(values.size());
			for (const double v : values) {
				squares += (v - mean) * (v - mean);
			}
			spreads.push_back(std::sqrt(squares / double(values.size())));
		}
	}
	return spreads.size() < 5 ? -1.0 : median_of(std::move(spreads));
}

// Offsets from a wall's top edge: into the ceiling (along p_inward) or down the wall.
std::vector<glm::dvec3> ceiling_offsets(const Vec2 &p_inward) {
	std::vector<glm::dvec3> offsets;
	for (const double in : { 0.06, 0.12, 0.2, 0.3 }) {
		offsets.emplace_back(p_inward.x * in, 0.0, p_inward.y * in);
	}
	return offsets;
}

std::vector<glm::dvec3> wall_offsets() {
	return { glm::dvec3(0.0, -0.06, 0.0), glm::dvec3(0.0, -0.12, 0.0), glm::dvec3(0.0, -0.2, 0.0), glm::dvec3(0.0, -0.3, 0.0) };
}

// A profile's cue of a real top edge: its edge strength over the median, times how much more
// alike than the median the views see the strip beside it.
double edge_cue(double p_edge, double p_edge_median, double p_spread, double p_spread_median) {
	return (p_edge / p_edge_median) * p_spread_median / (p_spread + 0.05 * p_spread_median);
}

// The peak of a profile, refined by a parabola through it and its neighbours (in steps), and its
// height over the profile's median.
double profile_peak(const std::vector<double> &p_profile, double *r_contrast, bool *r_inside) {
	const size_t best = size_t(std::max_element(p_profile.begin(), p_profile.end()) - p_profile.begin());
	const double median = median_of(p_profile);
	*r_contrast = median > 0.0 ? p_profile[best] / median : 0.0;
	*r_inside = best > 0 && best + 1 < p_profile.size();
	if (!*r_inside) {
		return double(best);
	}
	const double a = p_profile[best - 1], b = p_profile[best], c = p_profile[best + 1];
	const double curvature = a - 2.0 * b + c;
	return double(best) + (curvature < 0.0 ? std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5) : 0.0);
}

// How far p_peak stands above a profile's median, in robust standard deviations (1.4826 times
// the median absolute deviation); 0 for a flat profile.
double peak_sigmas(const std::vector<double> &p_profile, double p_peak) {
	const double median = median_of(p_profile);
	std::vector<double> deviations;
	deviations.reserve(p_profile.size());
	for (const double v : p_profile) {
		deviations.push_back(std::abs(v - median));
	}
	const double sigma = 1.4826 * median_of(std::move(deviations));
	return sigma > 0.0 ? (p_peak - median) / sigma : 0.0;
}

} // namespace

CeilingSearch ceiling_from_fisheye(const std::vector<FisheyeView> &p_views, const OmniParams &p_fisheye, const Floorplan &p_floorplan, double p_min_m,
		double p_max_m, const std::vector<double> &p_edge_confidence) {
	CeilingSearch result;
	const size_t corners = p_floorplan.points.size();
	if (p_views.empty() || corners < 3 || !(p_max_m > p_min_m)) {
		result.message = p_views.empty() ? "no fisheye frames with a pose" : "no floorplan, or an empty height range";
		return result;
	}
	EdgeViews edges(p_views, p_fisheye);
	result.views_used = edges.views.size();
	if (edges.views.empty()) {
		result.message = "no fisheye frame has the rig's fisheye size";
		return result;
	}
	const bool any_seen = std::any_of(p_edge_confidence.begin(), p_edge_confidence.end(), [](double c) { return c >= 0.3; });
	const bool counter_clockwise = polygon_signed_area_m2(p_floorplan.points) > 0.0;
	const int steps = int(std::floor((p_max_m - p_min_m) / STEP_M)) + 1;
	std::vector<double> combined(size_t(steps), 0.0);
	size_t in_view = 0;
	for (size_t i = 0; i < corners; i++) {
		if (any_seen && (i >= p_edge_confidence.size() || p_edge_confidence[i] < 0.3)) {
			continue;
		}
		const Vec2 &a = p_floorplan.points[i], &b = p_floorplan.points[(i + 1) % corners];
		const double length = std::hypot(b.x - a.x, b.y - a.y);
		const Vec2 inward = counter_clockwise ? Vec2{ -(b.y - a.y) / length, (b.x - a.x) / length } : Vec2{ (b.y - a.y) / length, -(b.x - a.x) / length };
		// Two cues per height: the edge's strength (a texture's horizontal lines have it too) and
		// how alike the views see the ceiling just inside (only the true height has that).
		const std::vector<glm::dvec3> offsets = ceiling_offsets(inward);
		edges.set_occluders(p_floorplan, p_edge_confidence, i, 0);
		std::vector<double> edge(size_t(steps), 0.0), spread(size_t(steps), 0.0);
		bool usable = true;
		for (int k = 0; k < steps && usable; k++) {
			edge[size_t(k)] = edges.segment_edge(a, b, p_min_m + STEP_M * k);
			spread[size_t(k)] = edges.strip_spread(a, b, p_min_m + STEP_M * k, offsets);
			usable = edge[size_t(k)] >= 0.0 && spread[size_t(k)] >= 0.0;
		}
		if (!usable) {
			continue;
		}
		in_view++;
		const double edge_median = median_of(edge), spread_median = median_of(spread);
		if (edge_median <= 0.0 || spread_median <= 0.0) { // the images show nothing along it
			continue;
		}
		for (int k = 0; k < steps; k++) {
			combined[size_t(k)] += edge_cue(edge[size_t(k)], edge_median, spread[size_t(k)], spread_median);
		}
		result.walls_used++;
	}
	if (result.walls_used == 0) {
		result.message = in_view == 0 ? "no wall's top edge is in the fisheye's view"
									  : format("no clear wall-ceiling edge between %.2f and %.2f m in the fisheye: the images show no edges along the walls", p_min_m,
												p_max_m);
		return result;
	}
	bool inside = false;
	const double peak = profile_peak(combined, &result.contrast, &inside);
	result.height_m = p_min_m + STEP_M * peak;
	result.ok = inside && result.contrast >= MIN_CONTRAST;
	result.message = result.ok ? format("the walls' top edge at %.3f m, %.1f times the median edge strength", result.height_m, result.contrast)
							   : format("no clear wall-ceiling edge between %.2f and %.2f m in the fisheye (the best, at %.2f m, ", p_min_m, p_max_m,
										 result.height_m) +
					format("%.1f times the median)", result.contrast);
	return result;
}

std::vector<std::string> complete_walls_from_fisheye(const std::vector<FisheyeView> &p_views, const OmniParams &p_fisheye, Floorplan *io_floorplan,
		std::vector<double> *io_edge_confidence, double p_max_move_m) {
	std::vector<std::string> lines;
	const size_t n = io_floorplan->points.size();
	const double height = io_floorplan->ceiling_height_m;
	if (n < 3 || io_edge_confidence->size() != n || !(height > 0.0)) {
		return lines;
	}
	EdgeViews edges(p_views, p_fisheye);
	if (edges.views.empty()) {
		return lines;
	}
	const bool counter_clockwise = polygon_signed_area_m2(io_floorplan->points) > 0.0;
	for (size_t i = 0; i < n; i++) {
		if ((*io_edge_confidence)[i] >= 0.3) {
			continue;
		}
		std::vector<Vec2> &points = io_floorplan->points;
		const Vec2 a = points[i], b = points[(i + 1) % n];
		const Vec2 before = points[(i + n - 1) % n], after = points[(i + 2) % n];
		const double length = std::hypot(b.x - a.x, b.y - a.y);
		const Vec2 along = { (b.x - a.x) / length, (b.y - a.y) / length };
		const Vec2 outward = counter_clockwise ? Vec2{ along.y, -along.x } : Vec2{ -along.y, along.x };
		// The corners slide along the neighbouring edges' lines: a + s * (a - before) meets the moved line.
		const Vec2 slide_a = { a.x - before.x, a.y - before.y }, slide_b = { b.x - after.x, b.y - after.y };
		const double rate_a = dot2(slide_a, outward), rate_b = dot2(slide_b, outward);
		if (std::abs(rate_a) < 1e-6 || std::abs(rate_b) < 1e-6) {
			lines.push_back("edge " + std::to_string(i) + ": a neighbouring edge runs along it; left as seen");
			continue;
		}
		auto moved = [&](double p_move_m, Vec2 *r_a, Vec2 *r_b) {
			*r_a = { a.x + slide_a.x * p_move_m / rate_a, a.y + slide_a.y * p_move_m / rate_a };
			*r_b = { b.x + slide_b.x * p_move_m / rate_b, b.y + slide_b.y * p_move_m / rate_b };
		};
		// The two cues, as for the ceiling, with the strip down the moved wall: the views agree
		// on it only where a wall stands. Its neighbours grow with it, so they hide nothing.
		edges.set_occluders(*io_floorplan, *io_edge_confidence, i, 1);
		const int steps = int(std::floor(p_max_move_m / STEP_M)) + 1;
		std::vector<double> edge(size_t(steps), 0.0), spread(size_t(steps), 0.0), profile(size_t(steps), 0.0);
		for (int k = 0; k < steps; k++) {
			Vec2 ma, mb;
			moved(STEP_M * k, &ma, &mb);
			edge[size_t(k)] = std::max(0.0, edges.segment_edge(ma, mb, height));
			spread[size_t(k)] = edges.strip_spread(ma, mb, height, wall_offsets());
		}
		const double edge_median = median_of(edge), spread_median = median_of(spread);
		for (int k = 0; k < steps; k++) {
			profile[size_t(k)] = edge_median > 0.0 && spread_median > 0.0 && spread[size_t(k)] >= 0.0
					? edge_cue(edge[size_t(k)], edge_median, spread[size_t(k)], spread_median)
					: 0.0;
		}
		double ratio = 0.0;
		bool inside = false;
		const double move_m = STEP_M * profile_peak(profile, &ratio, &inside);
		const double sigmas = peak_sigmas(profile, *std::max_element(profile.begin(), profile.end()));
		if (!(sigmas >= MIN_WALL_SIGMAS) || (!inside && move_m > 0.0)) {
			lines.push_back("edge " + std::to_string(i) +
					format(": no clear top edge within %.1f m beyond it (the best, %.2f m out, %.1f sigma above the median); left where the view ended", p_max_move_m,
							move_m, sigmas));
			continue;
		}
		Floorplan trial = *io_floorplan;
		moved(move_m, &trial.points[i], &trial.points[(i + 1) % n]);
		if (!check_floorplan(trial).ok) {
			lines.push_back("edge " + std::to_string(i) + format(": moving it %.2f m would fold the floorplan; left as seen", move_m));
			continue;
		}
		*io_floorplan = trial;
		(*io_edge_confidence)[i] = FISHEYE_WALL_CONFIDENCE;
		lines.push_back("edge " + std::to_string(i) + format(": a wall %.3f m beyond where the view ended, from the fisheye (%.1f sigma above the median edge)",
											 move_m, sigmas));
	}
	return lines;
}

} // namespace roomprobe
