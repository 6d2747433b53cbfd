// Step 4 of room_estimation.h: a given floorplan placed on the reconstructed walls.
#include "room_estimation.h"

#include "wall_planes.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <set>
#include <cmath>

namespace roomprobe {

using namespace room_planes;

namespace {

struct Edge {
	Vec2 a, b, inward;
};
constexpr double TAU_M = 0.10; // a sample farther than this from its edge is not that edge's

// The reconstructed walls' candidate samples (world frame: Y up): the vertical ones above the floor.
std::vector<FlatSample> vertical_samples(const std::vector<SurfaceSample> &p_world_samples, const RoomEstimationOptions &p_options) {
	const double sin_normal = std::sin(p_options.normal_tolerance_deg * DEG);
	std::vector<FlatSample> flat;
	for (const SurfaceSample &s : p_world_samples) {
		if (std::abs(s.normal.y) <= sin_normal && s.position_m.y > 0.05) {
			FlatSample f;
			f.position = { s.position_m.x, s.position_m.z };
			const double length = std::hypot(s.normal.x, s.normal.z);
			f.normal = { s.normal.x / length, s.normal.z / length };
			f.angle = std::atan2(f.normal.y, f.normal.x);
			f.area_m2 = s.area_m2;
			flat.push_back(f);
		}
	}
	return flat;
}

// Two walls that are not parallel fix a placement.
bool walls_cross(const std::vector<WallEstimate> &p_walls) {
	bool crossing = false;
	for (size_t i = 0; i < p_walls.size(); i++) {
		for (size_t j = i + 1; j < p_walls.size(); j++) {
			crossing = crossing || std::abs(p_walls[i].normal.x * p_walls[j].normal.y - p_walls[i].normal.y * p_walls[j].normal.x) >= 0.3;
		}
	}
	return crossing;
}

// The walls' own samples: what the given edges must fit.
std::vector<FlatSample> samples_on_walls(const std::vector<FlatSample> &p_flat, const std::vector<WallEstimate> &p_walls, const RoomEstimationOptions &p_options) {
	std::vector<FlatSample> wall_samples;
	for (const FlatSample &s : p_flat) {
		for (const WallEstimate &wall : p_walls) {
			if (dot2(s.normal, wall.normal) >= std::cos(p_options.normal_tolerance_deg * DEG) &&
					std::abs(dot2(wall.normal, s.position) - wall.offset_m) <= p_options.plane_tolerance_m) {
				wall_samples.push_back(s);
				break;
			}
		}
	}
	if (wall_samples.size() > 3000) { // an even subsample: the fit needs the walls' shape, not every triangle
		std::vector<FlatSample> thinned;
		const double step = double(wall_samples.size()) / 3000.0;
		for (double i = 0.0; size_t(i) < wall_samples.size(); i += step) {
			thinned.push_back(wall_samples[size_t(i)]);
		}
		wall_samples = thinned;
	}
	return wall_samples;
}

// The given polygon's edges turned by p_yaw and moved by p_t.
std::vector<Edge> placed_edges(const std::vector<Vec2> &p_given, double p_yaw, const Vec2 &p_t) {
	const size_t n = p_given.size();
	const double c = std::cos(p_yaw), s = std::sin(p_yaw);
	std::vector<Edge> edges;
	for (size_t i = 0; i < n; i++) {
		const Vec2 &a = p_given[i], &b = p_given[(i + 1) % n];
		Edge e;
		e.a = { c * a.x - s * a.y + p_t.x, s * a.x + c * a.y + p_t.y };
		e.b = { c * b.x - s * b.y + p_t.x, s * b.x + c * b.y + p_t.y };
		const double length = std::hypot(e.b.x - e.a.x, e.b.y - e.a.y);
		e.inward = { -(e.b.y - e.a.y) / length, (e.b.x - e.a.x) / length };
		edges.push_back(e);
	}
	return edges;
}

// A sample's distance to the nearest edge facing its way (point to segment).
double nearest_edge(const std::vector<Edge> &p_edges, const FlatSample &p_sample, size_t *r_edge) {
	double best = 1e9;
	for (size_t i = 0; i < p_edges.size(); i++) {
		const Edge &e = p_edges[i];
		if (dot2(e.inward, p_sample.normal) < std::cos(20.0 * DEG)) {
			continue;
		}
		const Vec2 d = { e.b.x - e.a.x, e.b.y - e.a.y };
		const double t = std::clamp(((p_sample.position.x - e.a.x) * d.x + (p_sample.position.y - e.a.y) * d.y) / dot2(d, d), 0.0, 1.0);
		const double distance = std::hypot(p_sample.position.x - (e.a.x + t * d.x), p_sample.position.y - (e.a.y + t * d.y));
		if (distance < best) {
			best = distance;
			*r_edge = i;
		}
	}
	return best;
}

// The area-weighted squared distances of p_scoring to the placed edges, each capped at TAU_M.
double placement_cost(const std::vector<Vec2> &p_given, const std::vector<FlatSample> &p_scoring, double p_yaw, const Vec2 &p_t) {
	const std::vector<Edge> edges = placed_edges(p_given, p_yaw, p_t);
	double sum = 0.0;
	for (const FlatSample &s : p_scoring) {
		size_t edge = 0;
		const double d = std::min(nearest_edge(edges, s, &edge), TAU_M);
		sum += s.area_m2 * d * d;
	}
	return sum;
}

// The yaws that turn a given edge onto a wall direction, each once (to within a degree).
std::vector<double> candidate_yaws(const std::vector<Vec2> &p_given, const std::vector<WallEstimate> &p_walls) {
	const size_t n = p_given.size();
	std::vector<double> yaws;
	for (size_t i = 0; i < n; i++) {
		const Vec2 &a = p_given[i], &b = p_given[(i + 1) % n];
		const double length = std::hypot(b.x - a.x, b.y - a.y);
		const double inward_angle = std::atan2((b.x - a.x) / length, -(b.y - a.y) / length);
		for (const WallEstimate &wall : p_walls) {
			const double yaw = wrap_angle(std::atan2(wall.normal.y, wall.normal.x) - inward_angle);
			if (std::none_of(yaws.begin(), yaws.end(), [&](double y) { return std::abs(wrap_angle(y - yaw)) < 1.0 * DEG; })) {
				yaws.push_back(yaw);
			}
		}
	}
	return yaws;
}

// The best scoring candidate: each yaw placed by two walls that are not parallel. Returns its cost
// (1e18 for none).
double best_placement(const std::vector<Vec2> &p_given, const std::vector<WallEstimate> &p_walls, const std::vector<FlatSample> &p_scoring,
		double *r_yaw, Vec2 *r_t) {
	double best_cost = 1e18;
	std::set<std::array<long, 3>> tried;
	for (const double yaw : candidate_yaws(p_given, p_walls)) {
		const std::vector<Edge> turned = placed_edges(p_given, yaw, { 0.0, 0.0 });
		for (size_t w1 = 0; w1 < p_walls.size(); w1++) {
			for (size_t w2 = w1 + 1; w2 < p_walls.size(); w2++) {
				const Vec2 &n1 = p_walls[w1].normal, &n2 = p_walls[w2].normal;
				const double det = n1.x * n2.y - n1.y * n2.x;
				if (std::abs(det) < 0.3) {
					continue;
				}
				for (const Edge &e1 : turned) {
					if (dot2(e1.inward, n1) < std::cos(2.0 * DEG)) {
						continue;
					}
					for (const Edge &e2 : turned) {
						if (dot2(e2.inward, n2) < std::cos(2.0 * DEG)) {
							continue;
						}
						// n1 . (a1 + t) = d1, n2 . (a2 + t) = d2
						const double r1 = p_walls[w1].offset_m - dot2(n1, e1.a), r2 = p_walls[w2].offset_m - dot2(n2, e2.a);
						const Vec2 t = { (r1 * n2.y - n1.y * r2) / det, (n1.x * r2 - r1 * n2.x) / det };
						// Collinear edges (a wall drawn in pieces) give the same placement: score it once.
						if (!tried.insert({ std::lround(yaw / (0.1 * DEG)), std::lround(t.x / 0.01), std::lround(t.y / 0.01) }).second) {
							continue;
						}
						const double c = placement_cost(p_given, p_scoring, yaw, t);
						if (c < best_cost) {
							best_cost = c;
							*r_yaw = yaw;
							*r_t = t;
						}
					}
				}
			}
		}
	}
	return best_cost;
}

// Refine: Gauss-Newton on point-to-line distances of the samples within TAU_M. r_rms, r_inlier_area:
// over the last iteration's inliers.
void refine_placement(const std::vector<Vec2> &p_given, const std::vector<FlatSample> &p_wall_samples, double *r_yaw, Vec2 *r_t,
		double *r_rms, double *r_inlier_area) {
	double best_yaw = *r_yaw, rms = 0.0, inlier_area = 0.0;
	Vec2 best_t = *r_t;
	for (int iteration = 0; iteration < 10; iteration++) {
		const std::vector<Edge> edges = placed_edges(p_given, best_yaw, best_t);
		cv::Matx33d normal_matrix = cv::Matx33d::zeros();
		cv::Vec3d rhs(0.0, 0.0, 0.0);
		double squares = 0.0;
		inlier_area = 0.0;
		for (const FlatSample &s : p_wall_samples) {
			size_t index = 0;
			if (nearest_edge(edges, s, &index) > TAU_M) {
				continue;
			}
			const Edge &e = edges[index];
			const Vec2 q_minus_a = { s.position.x - e.a.x, s.position.y - e.a.y };
			const double r = dot2(e.inward, q_minus_a); // the sample's signed distance from the edge's line
			// The edge's points are R(yaw) g + t: turning by d moves a by d perp(a - t) and its
			// normal by d perp(n); moving by dt moves a by dt.
			const double d_yaw = dot2(perp(e.inward), q_minus_a) - dot2(e.inward, perp({ e.a.x - best_t.x, e.a.y - best_t.y }));
			const cv::Vec3d jacobian(d_yaw, -e.inward.x, -e.inward.y);
			normal_matrix += s.area_m2 * jacobian * jacobian.t();
			rhs += -s.area_m2 * r * jacobian;
			squares += s.area_m2 * r * r;
			inlier_area += s.area_m2;
		}
		rms = inlier_area > 0.0 ? std::sqrt(squares / inlier_area) : 0.0;
		cv::Vec3d step;
		if (inlier_area <= 0.0 || !cv::solve(normal_matrix, rhs, step, cv::DECOMP_CHOLESKY)) {
			break;
		}
		best_yaw = wrap_angle(best_yaw + step[0]);
		best_t = { best_t.x + step[1], best_t.y + step[2] };
		if (std::abs(step[0]) < 1e-7 && std::hypot(step[1], step[2]) < 1e-7) {
			break;
		}
	}
	*r_yaw = best_yaw;
	*r_t = best_t;
	*r_rms = rms;
	*r_inlier_area = inlier_area;
}

} // namespace

FloorplanRegistration register_floorplan(const Floorplan &p_given, const std::vector<SurfaceSample> &p_world_samples, const RoomEstimationOptions &p_options) {
	FloorplanRegistration result;
	const FloorplanCheck check = check_floorplan(p_given);
	if (!check.ok) {
		result.message = "the given floorplan: " + check.message;
		return result;
	}
	std::vector<Vec2> given = p_given.points;
	if (polygon_signed_area_m2(given) < 0.0) {
		std::reverse(given.begin(), given.end());
	}
	const std::vector<FlatSample> flat = vertical_samples(p_world_samples, p_options);
	double axis = 0.0;
	bool manhattan = false;
	const std::vector<WallEstimate> walls = find_walls(flat, p_options, &axis, &manhattan);
	if (!walls_cross(walls)) {
		result.message = std::to_string(walls.size()) + " wall" + (walls.size() == 1 ? "" : "s") +
				" reconstructed, none across another: a placement needs two walls that are not parallel (sweep a corner)";
		return result;
	}
	const std::vector<FlatSample> wall_samples = samples_on_walls(flat, walls, p_options);
	double total = 0.0;
	for (const FlatSample &s : wall_samples) {
		total += s.area_m2;
	}
	// The candidates are scored on a few hundred samples (the refinement uses them all).
	std::vector<FlatSample> scoring;
	for (size_t i = 0; i < wall_samples.size(); i += std::max<size_t>(1, wall_samples.size() / 300)) {
		scoring.push_back(wall_samples[i]);
	}
	double best_yaw = 0.0;
	Vec2 best_t;
	if (best_placement(given, walls, scoring, &best_yaw, &best_t) >= 1e18) {
		result.message = "no wall of the given floorplan lines up with the reconstructed walls' directions";
		return result;
	}
	double rms = 0.0, inlier_area = 0.0;
	refine_placement(given, wall_samples, &best_yaw, &best_t, &rms, &inlier_area);
	result.ok = true;
	result.yaw_deg = best_yaw / DEG;
	result.residual_rms_m = rms;
	result.inlier_share = total > 0.0 ? inlier_area / total : 0.0;
	result.world_from_given.rotation = glm::angleAxis(-best_yaw, glm::dvec3(0.0, 1.0, 0.0)); // (x, z) turned by yaw: about Y by -yaw
	result.world_from_given.translation = glm::dvec3(best_t.x, 0.0, best_t.y);
	result.poor = rms > 0.03 || result.inlier_share < 0.5;
	result.message = format("placed with a %.2f cm residual over %.0f%% of the walls' surface", rms * 100.0, result.inlier_share * 100.0) +
			(result.poor ? ": a poor fit (is it the same room?)" : "");
	return result;
}

} // namespace roomprobe
