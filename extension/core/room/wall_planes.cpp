#include "wall_planes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace roomprobe::room_planes {

std::string format(const char *p_format, double p_a, double p_b, double p_c) {
	char text[256];
	std::snprintf(text, sizeof(text), p_format, p_a, p_b, p_c);
	return text;
}

double wrap_angle(double p_angle) { // to (-pi, pi]
	return std::remainder(p_angle, 2.0 * PI);
}

LineHistogram::LineHistogram(const std::vector<std::pair<double, double>> &p_values, double p_half_m) {
	if (p_values.empty()) {
		return;
	}
	double low = p_values.front().first, high = low;
	for (const auto &[value, weight] : p_values) {
		low = std::min(low, value);
		high = std::max(high, value);
	}
	start = low - p_half_m;
	const size_t bins = size_t(std::ceil((high - low + 2.0 * p_half_m) / BIN_M)) + 1;
	std::vector<double> counts(bins, 0.0);
	for (const auto &[value, weight] : p_values) {
		counts[std::min(bins - 1, size_t((value - start) / BIN_M))] += weight;
	}
	std::vector<double> prefix(bins + 1, 0.0);
	for (size_t i = 0; i < bins; i++) {
		prefix[i + 1] = prefix[i] + counts[i];
	}
	const long half = long(std::lround(p_half_m / BIN_M));
	window.resize(bins);
	for (long i = 0; i < long(bins); i++) {
		const long a = std::max(0L, i - half), b = std::min(long(bins), i + half + 1);
		window[size_t(i)] = prefix[size_t(b)] - prefix[size_t(a)];
	}
}

size_t LineHistogram::local_peak(size_t p_bin, double p_radius_m) const {
	const size_t radius = size_t(p_radius_m / BIN_M);
	size_t best = p_bin;
	for (size_t i = p_bin > radius ? p_bin - radius : 0; i < std::min(window.size(), p_bin + radius + 1); i++) {
		if (window[i] > window[best]) {
			best = i;
		}
	}
	return best;
}

// The weighted mean of the values within p_half_m of p_centre (the plane's refined offset).
double mean_near(const std::vector<std::pair<double, double>> &p_values, double p_centre, double p_half_m, double *r_rms, double *r_weight) {
	double sum = 0.0, weight = 0.0;
	for (const auto &[value, w] : p_values) {
		if (std::abs(value - p_centre) <= p_half_m) {
			sum += w * value;
			weight += w;
		}
	}
	const double mean = weight > 0.0 ? sum / weight : p_centre;
	if (r_rms != nullptr) {
		double squares = 0.0;
		for (const auto &[value, w] : p_values) {
			if (std::abs(value - p_centre) <= p_half_m) {
				squares += w * (value - mean) * (value - mean);
			}
		}
		*r_rms = weight > 0.0 ? std::sqrt(squares / weight) : 0.0;
	}
	if (r_weight != nullptr) {
		*r_weight = weight;
	}
	return mean;
}

// The value below which p_share of the weight lies.
double weighted_quantile(std::vector<std::pair<double, double>> p_values, double p_share) {
	std::sort(p_values.begin(), p_values.end());
	double total = 0.0;
	for (const auto &entry : p_values) {
		total += entry.second;
	}
	double seen = 0.0;
	for (const auto &[value, weight] : p_values) {
		seen += weight;
		if (seen >= p_share * total) {
			return value;
		}
	}
	return p_values.empty() ? 0.0 : p_values.back().first;
}


Vec2 from_angle(double p_angle) { return { std::cos(p_angle), std::sin(p_angle) }; }

// The normal directions walls take: histogram peaks of the vertical samples' normal angles
// (1-degree bins, +-p_tolerance windows), snapped to the dominant axis's multiples of 90 degrees
// when within p_snap. r_axis: the dominant direction (largest peak).
std::vector<double> wall_directions(const std::vector<FlatSample> &p_flat, const RoomEstimationOptions &p_options, double *r_axis, bool *r_manhattan,
		double p_axis_correction) {
	constexpr int BINS = 360;
	std::vector<double> counts(BINS, 0.0);
	std::vector<double> quarter(BINS / 4 * 2, 0.0); // angles mod 90, half-degree bins
	for (const FlatSample &s : p_flat) {
		const double degrees = (s.angle + PI) / DEG;
		counts[size_t(std::clamp(int(degrees), 0, BINS - 1))] += s.area_m2;
		const double q = std::fmod(degrees, 90.0);
		quarter[size_t(std::clamp(int(q * 2.0), 0, int(quarter.size()) - 1))] += s.area_m2;
	}
	// The dominant axis: the best mod-90 window, then the circular mean of 4 x angle within it.
	const int half = int(std::lround(p_options.manhattan_snap_deg * 2.0));
	double best = -1.0;
	int best_bin = 0;
	for (int i = 0; i < int(quarter.size()); i++) {
		double sum = 0.0;
		for (int k = -half; k <= half; k++) {
			sum += quarter[size_t((i + k + int(quarter.size())) % int(quarter.size()))];
		}
		if (sum > best) {
			best = sum;
			best_bin = i;
		}
	}
	// The window's centre of mass (not its centre: with one populated bin, every window holding it
	// ties), then the circular mean of 4 x angle about it, re-centred until it settles.
	double mass = 0.0, moment = 0.0;
	for (int k = -half; k <= half; k++) {
		const double weight = quarter[size_t((best_bin + k + int(quarter.size())) % int(quarter.size()))];
		mass += weight;
		moment += weight * (best_bin + k + 0.5);
	}
	double estimate = (mass > 0.0 ? moment / mass : best_bin + 0.5) * 0.5 * DEG - PI; // mod 90 degrees it is all the same
	for (int iteration = 0; iteration < 5; iteration++) {
		double c = 0.0, s4 = 0.0;
		for (const FlatSample &s : p_flat) {
			if (std::abs(std::remainder(s.angle - estimate, PI / 2.0)) <= p_options.manhattan_snap_deg * DEG) {
				c += s.area_m2 * std::cos(4.0 * s.angle);
				s4 += s.area_m2 * std::sin(4.0 * s.angle);
			}
		}
		if (c == 0.0 && s4 == 0.0) {
			break;
		}
		estimate = std::atan2(s4, c) / 4.0;
	}
	const double axis = std::remainder(estimate, PI / 2.0) + p_axis_correction;
	*r_axis = axis;

	// Direction peaks: +-tolerance windows over the circular histogram.
	const int window = int(std::lround(p_options.normal_tolerance_deg / 2.0));
	std::vector<double> sums(BINS, 0.0);
	for (int i = 0; i < BINS; i++) {
		for (int k = -window; k <= window; k++) {
			sums[size_t(i)] += counts[size_t((i + k + BINS) % BINS)];
		}
	}
	std::vector<int> order(BINS);
	std::iota(order.begin(), order.end(), 0);
	std::sort(order.begin(), order.end(), [&](int a, int b) { return sums[size_t(a)] > sums[size_t(b)]; });
	std::vector<double> directions;
	bool manhattan = true;
	for (const int bin : order) {
		if (sums[size_t(bin)] < p_options.wall_min_area_m2) {
			break;
		}
		const double angle = (bin + 0.5) * DEG - PI;
		bool near = false;
		for (const double taken : directions) {
			near = near || std::abs(wrap_angle(angle - taken)) < 2.0 * p_options.normal_tolerance_deg * DEG;
		}
		if (near) {
			continue;
		}
		// Refine: the circular mean of the samples within the tolerance.
		double cx = 0.0, cy = 0.0;
		for (const FlatSample &s : p_flat) {
			if (std::abs(wrap_angle(s.angle - angle)) <= p_options.normal_tolerance_deg * DEG) {
				cx += s.area_m2 * std::cos(s.angle);
				cy += s.area_m2 * std::sin(s.angle);
			}
		}
		double refined = std::atan2(cy, cx);
		const double off_axis = std::remainder(refined - axis, PI / 2.0);
		if (std::abs(off_axis) <= p_options.manhattan_snap_deg * DEG) {
			refined = wrap_angle(refined - off_axis);
		} else {
			manhattan = false;
		}
		directions.push_back(refined);
	}
	*r_manhattan = manhattan;
	return directions;
}

// The walls along one normal direction: offset peaks with enough area seen and wide enough,
// the outermost kept where several overlap (a table's side or a wardrobe's front stands in front
// of the wall behind it).
std::vector<WallEstimate> walls_along(const std::vector<FlatSample> &p_flat, double p_direction, const RoomEstimationOptions &p_options) {
	const Vec2 normal = from_angle(p_direction);
	const Vec2 along = perp(normal);
	std::vector<std::pair<double, double>> offsets;
	std::vector<const FlatSample *> members;
	for (const FlatSample &s : p_flat) {
		if (std::abs(wrap_angle(s.angle - p_direction)) <= p_options.normal_tolerance_deg * DEG) {
			offsets.emplace_back(dot2(normal, s.position), s.area_m2);
			members.push_back(&s);
		}
	}
	std::vector<WallEstimate> found;
	if (offsets.empty()) {
		return found;
	}
	const LineHistogram histogram(offsets, p_options.plane_tolerance_m);
	std::vector<size_t> order(histogram.window.size());
	std::iota(order.begin(), order.end(), size_t(0));
	std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return histogram.window[a] > histogram.window[b]; });
	std::vector<double> peaks;
	for (const size_t bin : order) {
		if (histogram.window[bin] < p_options.wall_min_area_m2) {
			break;
		}
		const double centre = histogram.centre(bin);
		if (std::any_of(peaks.begin(), peaks.end(), [&](double p) { return std::abs(p - centre) < 0.15; })) {
			continue;
		}
		peaks.push_back(centre);
		WallEstimate wall;
		wall.normal = normal;
		wall.offset_m = mean_near(offsets, mean_near(offsets, centre, 2.0 * p_options.plane_tolerance_m), p_options.plane_tolerance_m, &wall.rms_m, &wall.area_m2);
		std::vector<std::pair<double, double>> extent;
		for (size_t i = 0; i < offsets.size(); i++) {
			if (std::abs(offsets[i].first - wall.offset_m) <= p_options.plane_tolerance_m) {
				extent.emplace_back(dot2(along, members[i]->position), members[i]->area_m2);
			}
		}
		// The 1 % and 99 % points, widened by what they cut off of an evenly seen wall.
		const double low = weighted_quantile(extent, 0.01), high = weighted_quantile(extent, 0.99);
		wall.from_m = low - 0.01 * (high - low) / 0.98;
		wall.to_m = high + 0.01 * (high - low) / 0.98;
		if (wall.to_m - wall.from_m >= p_options.wall_min_width_m) {
			found.push_back(wall);
		}
	}
	return found;
}

namespace {

// The overlap of two walls' seen extents, in p_wall's own parameter along it.
double extent_overlap(const WallEstimate &p_wall, const WallEstimate &p_other) {
	const bool same = dot2(p_wall.normal, p_other.normal) > 0.0;
	const double from = same ? p_other.from_m : -p_other.to_m, to = same ? p_other.to_m : -p_other.from_m;
	return std::min(p_wall.to_m, to) - std::max(p_wall.from_m, from);
}

} // namespace

std::vector<WallEstimate> keep_outermost(const std::vector<WallEstimate> &p_candidates) {
	std::vector<WallEstimate> kept;
	for (const WallEstimate &wall : p_candidates) {
		const double width = wall.to_m - wall.from_m;
		bool hidden = false, partition = false;
		for (const WallEstimate &other : p_candidates) {
			const double c = dot2(wall.normal, other.normal);
			if (c > std::cos(2.0 * DEG)) { // behind it, facing the same way
				hidden = hidden || (other.offset_m < wall.offset_m - 0.15 && extent_overlap(wall, other) > 0.3 * width);
			} else if (c < -std::cos(2.0 * DEG)) { // its back, close behind: a partition's two faces
				const double thickness = wall.offset_m + other.offset_m; // n.p = offset and -n.p = other's
				partition = partition || (thickness > 0.0 && thickness <= PARTITION_MAX_THICKNESS_M && extent_overlap(wall, other) > 0.3 * width);
			}
		}
		if (!hidden || partition) {
			kept.push_back(wall);
		}
	}
	return kept;
}

std::vector<WallEstimate> find_walls(const std::vector<FlatSample> &p_flat, const RoomEstimationOptions &p_options, double *r_axis, bool *r_manhattan,
		double p_axis_correction) {
	std::vector<WallEstimate> walls;
	for (const double direction : wall_directions(p_flat, p_options, r_axis, r_manhattan, p_axis_correction)) {
		const std::vector<WallEstimate> along = walls_along(p_flat, direction, p_options);
		walls.insert(walls.end(), along.begin(), along.end());
	}
	return keep_outermost(walls);
}

} // namespace roomprobe::room_planes
