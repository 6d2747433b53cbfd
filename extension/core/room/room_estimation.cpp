#include "room_estimation.h"

#include "room_polygon.h"
#include "wall_planes.h"

#include <slam/marching_cubes.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace roomprobe {

namespace {

using namespace room_planes;

// Up: the area-weighted mean of the normals near the hint (floor, table tops and ceiling all
// share it), in narrowing windows.
glm::dvec3 refine_up(const std::vector<SurfaceSample> &p_samples, glm::dvec3 p_up) {
	for (const double window_deg : { 35.0, 15.0, 6.0 }) {
		glm::dvec3 sum(0.0);
		for (const SurfaceSample &sample : p_samples) {
			const double c = glm::dot(sample.normal, p_up);
			if (std::abs(c) >= std::cos(window_deg * DEG)) {
				sum += (c > 0.0 ? sample.normal : -sample.normal) * sample.area_m2;
			}
		}
		if (glm::length(sum) <= 0.0) {
			break;
		}
		p_up = glm::normalize(sum);
	}
	return p_up;
}

// The normal of the best plane through weighted points (the smallest eigenvector of their covariance).
glm::dvec3 plane_normal(const std::vector<SurfaceSample> &p_points, const glm::dvec3 &p_side) {
	glm::dvec3 mean(0.0);
	double weight = 0.0;
	for (const SurfaceSample &s : p_points) {
		mean += s.area_m2 * s.position_m;
		weight += s.area_m2;
	}
	mean /= weight;
	cv::Matx33d covariance = cv::Matx33d::zeros();
	for (const SurfaceSample &s : p_points) {
		const glm::dvec3 d = s.position_m - mean;
		for (int r = 0; r < 3; r++) {
			for (int c = 0; c < 3; c++) {
				covariance(r, c) += s.area_m2 * d[r] * d[c];
			}
		}
	}
	cv::Mat values, vectors;
	cv::eigen(cv::Mat(covariance), values, vectors); // descending
	glm::dvec3 normal(vectors.at<double>(2, 0), vectors.at<double>(2, 1), vectors.at<double>(2, 2));
	normal = glm::normalize(normal);
	return glm::dot(normal, p_side) < 0.0 ? -normal : normal;
}

// The angle (radians) from the wall's normal to the normal of the line its points follow (2-D
// principal axis of its inliers).
double wall_line_residual(const std::vector<FlatSample> &p_flat, const WallEstimate &p_wall, const RoomEstimationOptions &p_options) {
	double weight = 0.0;
	Vec2 mean;
	std::vector<const FlatSample *> inliers;
	for (const FlatSample &s : p_flat) {
		if (dot2(s.normal, p_wall.normal) >= std::cos(p_options.normal_tolerance_deg * DEG) &&
				std::abs(dot2(p_wall.normal, s.position) - p_wall.offset_m) <= p_options.plane_tolerance_m) {
			inliers.push_back(&s);
			mean = { mean.x + s.area_m2 * s.position.x, mean.y + s.area_m2 * s.position.y };
			weight += s.area_m2;
		}
	}
	if (inliers.size() < 10) {
		return 0.0;
	}
	mean = { mean.x / weight, mean.y / weight };
	double xx = 0.0, xy = 0.0, yy = 0.0;
	for (const FlatSample *s : inliers) {
		const double dx = s->position.x - mean.x, dy = s->position.y - mean.y;
		xx += s->area_m2 * dx * dx;
		xy += s->area_m2 * dx * dy;
		yy += s->area_m2 * dy * dy;
	}
	const double line_angle = 0.5 * std::atan2(2.0 * xy, xx - yy); // the principal axis
	const double normal_angle = line_angle + PI / 2.0;
	return std::remainder(normal_angle - std::atan2(p_wall.normal.y, p_wall.normal.x), PI / 2.0);
}

} // namespace

const char *room_estimate_state_name(RoomEstimateState p_state) {
	switch (p_state) {
		case RoomEstimateState::Complete:
			return "complete";
		case RoomEstimateState::Partial:
			return "partial";
		case RoomEstimateState::NoSurface:
			return "no surface";
		case RoomEstimateState::NoFloor:
			return "no floor";
		case RoomEstimateState::TooFewWalls:
			return "too few walls";
	}
	return "unknown";
}

std::vector<SurfaceSample> surface_samples(const TriangleMesh &p_mesh) {
	std::vector<SurfaceSample> samples;
	samples.reserve(p_mesh.indices.size() / 3);
	for (size_t i = 0; i + 2 < p_mesh.indices.size(); i += 3) {
		const glm::dvec3 a(p_mesh.vertices[p_mesh.indices[i]]), b(p_mesh.vertices[p_mesh.indices[i + 1]]), c(p_mesh.vertices[p_mesh.indices[i + 2]]);
		const glm::dvec3 cross = glm::cross(b - a, c - a);
		const double twice_area = glm::length(cross);
		if (!(twice_area > 0.0)) {
			continue;
		}
		SurfaceSample sample;
		sample.position_m = (a + b + c) / 3.0;
		sample.normal = cross / twice_area; // counter-clockwise seen from the free side: towards free space
		sample.area_m2 = 0.5 * twice_area;
		samples.push_back(sample);
	}
	return samples;
}

std::vector<SurfaceSample> transform_samples(const std::vector<SurfaceSample> &p_samples, const Pose &p_pose) {
	std::vector<SurfaceSample> out = p_samples;
	for (SurfaceSample &s : out) {
		s.position_m = transform_point(p_pose, s.position_m);
		s.normal = p_pose.rotation * s.normal;
	}
	return out;
}

std::vector<double> floorplan_edge_confidence(const std::vector<Vec2> &p_points, const std::vector<WallEstimate> &p_walls) {
	std::vector<double> confidence(p_points.size(), 0.0);
	const bool counter_clockwise = polygon_signed_area_m2(p_points) > 0.0;
	for (size_t i = 0; i < p_points.size(); i++) {
		confidence[i] = wall_cover(p_points[i], p_points[(i + 1) % p_points.size()], counter_clockwise, p_walls);
	}
	return confidence;
}

void merge_floorplan_steps(std::vector<Vec2> *io_points, std::vector<double> *io_confidence, double p_max_step_m) {
	std::vector<Vec2> &points = *io_points;
	std::vector<double> &confidence = *io_confidence;
	if (confidence.size() != points.size()) {
		return;
	}
	auto sub = [](const Vec2 &p_a, const Vec2 &p_b) { return Vec2{ p_a.x - p_b.x, p_a.y - p_b.y }; };
	auto length_of = [](const Vec2 &p_v) { return std::hypot(p_v.x, p_v.y); };
	for (bool merged = true; merged && points.size() > 4;) {
		merged = false;
		const size_t n = points.size();
		for (size_t i = 0; i < n && !merged; i++) {
			// Edges: before (P0 -> P1), the step (P1 -> P2), after (P2 -> P3), with P1 = points[i].
			const size_t i0 = (i + n - 1) % n, i2 = (i + 1) % n, i3 = (i + 2) % n;
			const Vec2 before = sub(points[i], points[i0]), step = sub(points[i2], points[i]), after = sub(points[i3], points[i2]);
			const double before_m = length_of(before), step_m = length_of(step), after_m = length_of(after);
			if (!(step_m < p_max_step_m) || !(before_m > step_m) || !(after_m > step_m) ||
					dot2(before, after) < std::cos(2.0 * DEG) * before_m * after_m) {
				continue;
			}
			// The shorter edge moves across onto the longer one's line.
			const bool move_after = after_m <= before_m;
			const Vec2 along = move_after ? Vec2{ after.x / after_m, after.y / after_m } : Vec2{ before.x / before_m, before.y / before_m };
			const Vec2 gap = move_after ? sub(points[i], points[i2]) : sub(points[i2], points[i]);
			const double a = dot2(gap, along);
			const Vec2 shift = { gap.x - a * along.x, gap.y - a * along.y };
			const size_t moved[2] = { move_after ? i2 : i0, move_after ? i3 : i };
			for (const size_t k : moved) {
				points[k] = { points[k].x + shift.x, points[k].y + shift.y };
			}
			// P1 and P2 now lie on the joined edge P0 -> P3: both go. Edge k runs from point k, so the
			// step (edge i) and after (edge i2) go with them, and before carries the joined confidence.
			confidence[i0] = (confidence[i0] * before_m + confidence[i2] * after_m) / (before_m + after_m);
			for (const size_t k : { std::max(i, i2), std::min(i, i2) }) { // the higher index first
				points.erase(points.begin() + ptrdiff_t(k));
				confidence.erase(confidence.begin() + ptrdiff_t(k));
			}
			merged = true;
		}
	}
}

void rebase_room_origin(RoomEstimate *io_estimate) {
	std::vector<Vec2> &points = io_estimate->floorplan.points;
	if (points.empty()) {
		return;
	}
	Vec2 low = points.front();
	for (const Vec2 &p : points) {
		low = { std::min(low.x, p.x), std::min(low.y, p.y) };
	}
	for (Vec2 &p : points) {
		p = { p.x - low.x, p.y - low.y };
	}
	for (WallEstimate &wall : io_estimate->walls) {
		wall.offset_m -= dot2(wall.normal, low);
		const double shift = dot2(perp(wall.normal), low);
		wall.from_m -= shift;
		wall.to_m -= shift;
	}
	io_estimate->world_from_model.translation -= glm::dvec3(low.x, 0.0, low.y);
}

RoomEstimate estimate_room(const std::vector<SurfaceSample> &p_samples, const glm::dvec3 &p_up_hint, const std::vector<glm::dvec3> &p_camera_positions,
		const RoomEstimationOptions &p_options) {
	RoomEstimate result;
	double total_area = 0.0;
	for (const SurfaceSample &s : p_samples) {
		total_area += s.area_m2;
	}
	if (p_samples.empty() || total_area < p_options.floor_min_area_m2) {
		result.state = RoomEstimateState::NoSurface;
		result.message = format("the dense model holds %.2f m2 of surface: sweep the room first", total_area);
		return result;
	}
	const double hint_length = glm::length(p_up_hint);
	const glm::dvec3 hint = hint_length > 0.0 && std::isfinite(hint_length) ? p_up_hint / hint_length : glm::dvec3(0.0, 1.0, 0.0);
	glm::dvec3 up = refine_up(p_samples, hint);
	const double cos_normal = std::cos(p_options.normal_tolerance_deg * DEG);

	// 1. The floor: the lowest horizontal, upward-facing plane with floor_min_area_m2 seen.
	auto floor_heights = [&](const glm::dvec3 &p_up) {
		std::vector<std::pair<double, double>> heights;
		for (const SurfaceSample &s : p_samples) {
			if (glm::dot(s.normal, p_up) >= cos_normal) {
				heights.emplace_back(glm::dot(s.position_m, p_up), s.area_m2);
			}
		}
		return heights;
	};
	double floor_height = 0.0;
	bool found_floor = false;
	glm::dvec3 first_up = up; // pass 0's up and floor, kept should pass 1 find no floor
	double first_height = 0.0, first_seen = 0.0;
	for (int pass = 0; pass < 2; pass++) { // again with the up the floor's own plane gives
		if (pass == 1) {
			found_floor = false;
		}
		const std::vector<std::pair<double, double>> heights = floor_heights(up);
		if (heights.empty()) {
			break;
		}
		const LineHistogram histogram(heights, p_options.plane_tolerance_m);
		size_t bin = 0;
		while (bin < histogram.window.size() && histogram.window[bin] < p_options.floor_min_area_m2) {
			bin++;
		}
		if (bin == histogram.window.size()) {
			break;
		}
		bin = histogram.local_peak(bin, 0.1);
		floor_height = mean_near(heights, mean_near(heights, histogram.centre(bin), 2.0 * p_options.plane_tolerance_m), p_options.plane_tolerance_m,
				&result.floor_rms_m, &result.floor_seen_m2);
		std::vector<SurfaceSample> floor;
		for (const SurfaceSample &s : p_samples) {
			if (glm::dot(s.normal, up) >= cos_normal && std::abs(glm::dot(s.position_m, up) - floor_height) <= p_options.plane_tolerance_m) {
				floor.push_back(s);
			}
		}
		found_floor = result.floor_seen_m2 > 0.0;
		if (pass == 0 && found_floor) {
			first_up = up;
			first_height = floor_height;
			first_seen = result.floor_seen_m2;
			if (floor.size() >= 3) {
				up = plane_normal(floor, up);
			}
		}
	}
	if (!found_floor && first_seen > 0.0) { // pass 1 lost the floor pass 0 had
		up = first_up;
		floor_height = first_height;
		result.floor_seen_m2 = first_seen;
		found_floor = true;
	}
	if (!found_floor || !(result.floor_seen_m2 > 0.0)) {
		result.state = RoomEstimateState::NoFloor;
		result.message = format("no horizontal plane with %.1f m2 seen: the floor was not in the sweep", p_options.floor_min_area_m2);
		return result;
	}
	for (const glm::dvec3 &camera : p_camera_positions) {
		if (glm::dot(camera, up) - floor_height < 0.2) {
			result.state = RoomEstimateState::NoFloor;
			result.message = format("a camera position is only %.2f m above the lowest large horizontal plane: not a floor under the sweep",
					glm::dot(camera, up) - floor_height);
			return result;
		}
	}

	// 2. Walls: vertical samples in 2-D, their directions, and the planes along each.
	glm::dvec3 e1 = std::abs(up.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
	e1 = glm::normalize(e1 - glm::dot(e1, up) * up);
	glm::dvec3 e3 = glm::cross(e1, up);
	const double sin_normal = std::sin(p_options.normal_tolerance_deg * DEG);
	auto flatten = [&](const glm::dvec3 &p_e1, const glm::dvec3 &p_e3) {
		std::vector<FlatSample> flat;
		for (const SurfaceSample &s : p_samples) {
			const double vertical = glm::dot(s.normal, up);
			const double height = glm::dot(s.position_m, up) - floor_height;
			if (std::abs(vertical) <= sin_normal && height > 0.05) {
				FlatSample f;
				f.position = { glm::dot(s.position_m, p_e1), glm::dot(s.position_m, p_e3) };
				const Vec2 n = { glm::dot(s.normal, p_e1), glm::dot(s.normal, p_e3) };
				const double length = std::hypot(n.x, n.y);
				f.normal = { n.x / length, n.y / length };
				f.angle = std::atan2(f.normal.y, f.normal.x);
				f.area_m2 = s.area_m2;
				flat.push_back(f);
			}
		}
		return flat;
	};
	// The world's x axis along the dominant wall normal: the normals' mean first, then the walls'
	// own points, far better (a line through metres of surface; marching cubes' normals scatter
	// by degrees), until the walls lie on the axes.
	std::vector<FlatSample> flat;
	std::vector<WallEstimate> walls;
	for (int pass = 0; pass < 4; pass++) {
		flat = flatten(e1, e3);
		double axis = 0.0;
		walls = find_walls(flat, p_options, &axis, &result.manhattan);
		double residual = 0.0, weight = 0.0;
		for (const WallEstimate &wall : walls) { // the walls on the axes (snapped to them)
			if (std::abs(std::remainder(std::atan2(wall.normal.y, wall.normal.x) - axis, PI / 2.0)) < 1e-9) {
				const double w = wall.area_m2 * (wall.to_m - wall.from_m) * (wall.to_m - wall.from_m);
				residual += w * wall_line_residual(flat, wall, p_options);
				weight += w;
			}
		}
		const double correction = weight > 0.0 ? residual / weight : 0.0;
		const double turn = axis + correction;
		if (std::abs(turn) < 1e-5 || pass == 3) { // the walls again, on the axes their lines give
			walls = find_walls(flat, p_options, &axis, &result.manhattan, correction);
			break;
		}
		e1 = glm::normalize(std::cos(turn) * e1 + std::sin(turn) * e3);
		e3 = glm::cross(e1, up);
	}

	// Where the floor was seen, and where the camera went.
	FloorGrid grid;
	grid.cell = p_options.floor_cell_m;
	std::vector<Vec2> floor_points;
	for (const SurfaceSample &s : p_samples) {
		if (glm::dot(s.normal, up) >= cos_normal && std::abs(glm::dot(s.position_m, up) - floor_height) <= p_options.plane_tolerance_m) {
			floor_points.push_back({ glm::dot(s.position_m, e1), glm::dot(s.position_m, e3) });
		}
	}
	std::vector<Vec2> cameras;
	for (const glm::dvec3 &camera : p_camera_positions) {
		cameras.push_back({ glm::dot(camera, e1), glm::dot(camera, e3) });
	}
	if (floor_points.empty()) {
		result.state = RoomEstimateState::NoFloor;
		result.message = "no floor seen within the plane's tolerance: the floor was not in the sweep";
		return result;
	}
	Vec2 low = floor_points.front(), high = low;
	for (const Vec2 &p : floor_points) {
		low = { std::min(low.x, p.x), std::min(low.y, p.y) };
		high = { std::max(high.x, p.x), std::max(high.y, p.y) };
	}
	grid.origin = low;
	grid.width = int(std::ceil((high.x - low.x) / grid.cell)) + 1;
	grid.height = int(std::ceil((high.y - low.y) / grid.cell)) + 1;
	grid.seen.assign(size_t(grid.width) * size_t(grid.height), 0);
	for (const Vec2 &p : floor_points) {
		const int x = int((p.x - low.x) / grid.cell), y = int((p.y - low.y) / grid.cell);
		grid.seen[size_t(y) * size_t(grid.width) + size_t(x)] = 1;
	}

	std::vector<double> distinct;
	for (const WallEstimate &wall : walls) {
		const double angle = std::atan2(wall.normal.y, wall.normal.x);
		if (std::none_of(distinct.begin(), distinct.end(), [&](double a) { return std::abs(wrap_angle(a - angle)) < 5.0 * DEG; })) {
			distinct.push_back(angle);
		}
	}
	std::vector<Vec2> polygon = distinct.size() >= 3 ? room_polygon(walls, grid, cameras, p_options) : std::vector<Vec2>();
	if (polygon.size() < 3) {
		result.state = RoomEstimateState::TooFewWalls;
		result.message = std::to_string(walls.size()) + " wall" + (walls.size() == 1 ? "" : "s") + " seen, facing " + std::to_string(distinct.size()) +
				" direction" + (distinct.size() == 1 ? "" : "s") + ": they do not close a room; sweep the walls all round";
		return result;
	}
	// The world: y = 0 on the floor, axes e1, up, e3 (origin moved to the floorplan's corner below).
	glm::dmat3 rows(e1, up, e3); // columns e1, up, e3: model_from_world's rotation
	const glm::dmat3 world_from_model_rotation = glm::transpose(rows);
	result.world_from_model.rotation = glm::normalize(glm::quat_cast(world_from_model_rotation));
	result.world_from_model.translation = -(world_from_model_rotation * (floor_height * up));
	result.floorplan.points = polygon;
	result.walls = walls;
	rebase_room_origin(&result);
	result.edge_confidence = floorplan_edge_confidence(result.floorplan.points, result.walls);
	std::vector<size_t> unseen;
	for (size_t i = 0; i < result.edge_confidence.size(); i++) {
		if (result.edge_confidence[i] < 0.3) {
			unseen.push_back(i);
		}
	}

	// 3. The ceiling, when the dense model holds it: the highest large downward-facing plane.
	std::vector<std::pair<double, double>> ceiling;
	for (const SurfaceSample &s : p_samples) {
		const double height = glm::dot(s.position_m, up) - floor_height;
		if (glm::dot(s.normal, up) <= -cos_normal && height >= p_options.min_ceiling_height_m && height <= p_options.max_ceiling_height_m) {
			ceiling.emplace_back(height, s.area_m2);
		}
	}
	if (!ceiling.empty()) {
		const LineHistogram histogram(ceiling, p_options.plane_tolerance_m);
		size_t bin = histogram.window.size();
		while (bin > 0 && histogram.window[bin - 1] < p_options.ceiling_min_area_m2) {
			bin--;
		}
		if (bin > 0) {
			const size_t peak = histogram.local_peak(bin - 1, 0.1);
			result.floorplan.ceiling_height_m =
					mean_near(ceiling, mean_near(ceiling, histogram.centre(peak), 2.0 * p_options.plane_tolerance_m), p_options.plane_tolerance_m);
			result.ceiling_source = "dense model";
		}
	}

	const bool closed = unseen.empty();
	result.state = closed && result.floorplan.ceiling_height_m > 0.0 ? RoomEstimateState::Complete : RoomEstimateState::Partial;
	result.message = std::to_string(polygon.size()) + " corners, " + std::to_string(walls.size()) + " walls" + (result.manhattan ? " (at right angles)" : "");
	if (!closed) {
		result.message += "; never seen as walls: edge";
		for (const size_t i : unseen) {
			result.message += " " + std::to_string(i);
		}
		result.message += " (the room ends there where the sweep's view did)";
	}
	if (result.floorplan.ceiling_height_m <= 0.0) {
		result.message += "; the ceiling was not in the dense model";
	}
	return result;
}

RoomComparison compare_rooms(const Floorplan &p_estimate, const Pose &p_estimate_world_from_model, const Floorplan &p_truth,
		const Pose &p_true_world_from_model) {
	RoomComparison result;
	const Pose true_from_estimate = compose(p_true_world_from_model, inverse(p_estimate_world_from_model));
	std::vector<Vec2> mapped;
	for (const Vec2 &p : p_estimate.points) {
		const glm::dvec3 q = transform_point(true_from_estimate, glm::dvec3(p.x, 0.0, p.y));
		mapped.push_back({ q.x, q.z });
	}
	const auto distance = [](const Vec2 &p_a, const Vec2 &p_b) { return std::hypot(p_a.x - p_b.x, p_a.y - p_b.y); };
	// The point of a non-empty p_set nearest p_point.
	const auto closest = [&](const Vec2 &p_point, const std::vector<Vec2> &p_set) -> const Vec2 & {
		const Vec2 *best = &p_set.front();
		for (const Vec2 &q : p_set) {
			best = distance(p_point, q) < distance(p_point, *best) ? &q : best;
		}
		return *best;
	};
	const auto nearest = [&](const Vec2 &p_point, const std::vector<Vec2> &p_set) { return p_set.empty() ? 1e9 : distance(p_point, closest(p_point, p_set)); };
	auto corner_error = [&](const std::vector<Vec2> &p_points) {
		double error = 0.0;
		for (const Vec2 &p : p_points) {
			error = std::max(error, nearest(p, p_truth.points));
		}
		for (const Vec2 &p : p_truth.points) {
			error = std::max(error, nearest(p, p_points));
		}
		return error;
	};
	result.corner_error_max_m = corner_error(mapped);
	// The best turn and shift: each corner paired with its nearest true one, fitted in closed form
	// (2-D Procrustes), three times over as the pairs settle.
	std::vector<Vec2> fitted = mapped;
	for (int round = 0; round < 3 && !fitted.empty() && !p_truth.points.empty(); round++) {
		std::vector<std::pair<Vec2, Vec2>> pairs;
		Vec2 mean_a, mean_b;
		for (const Vec2 &p : fitted) {
			const Vec2 &q = closest(p, p_truth.points);
			pairs.emplace_back(p, q);
			mean_a = { mean_a.x + p.x, mean_a.y + p.y };
			mean_b = { mean_b.x + q.x, mean_b.y + q.y };
		}
		const double n = double(pairs.size());
		mean_a = { mean_a.x / n, mean_a.y / n };
		mean_b = { mean_b.x / n, mean_b.y / n };
		double cross = 0.0, dot = 0.0;
		for (const auto &[a, b] : pairs) {
			const Vec2 u = { a.x - mean_a.x, a.y - mean_a.y }, v = { b.x - mean_b.x, b.y - mean_b.y };
			cross += u.x * v.y - u.y * v.x;
			dot += u.x * v.x + u.y * v.y;
		}
		const double angle = std::atan2(cross, dot), c = std::cos(angle), s = std::sin(angle);
		for (Vec2 &p : fitted) {
			const Vec2 u = { p.x - mean_a.x, p.y - mean_a.y };
			p = { mean_b.x + c * u.x - s * u.y, mean_b.y + s * u.x + c * u.y };
		}
	}
	result.corner_error_fitted_m = corner_error(fitted);
	result.corners = mapped.size();
	result.true_corners = p_truth.points.size();
	result.ceiling_error_m = std::abs(p_estimate.ceiling_height_m - p_truth.ceiling_height_m);
	const glm::dvec3 up_estimate = glm::inverse(p_estimate_world_from_model.rotation) * glm::dvec3(0.0, 1.0, 0.0);
	const glm::dvec3 up_true = glm::inverse(p_true_world_from_model.rotation) * glm::dvec3(0.0, 1.0, 0.0);
	result.up_error_deg = std::acos(std::clamp(glm::dot(up_estimate, up_true), -1.0, 1.0)) / DEG;
	return result;
}

} // namespace roomprobe
