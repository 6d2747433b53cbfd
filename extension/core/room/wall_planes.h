#pragma once
// Internal to the room module: vertical planes in the dense model (room_estimation.cpp finds
// the walls with them, floorplan_registration.cpp fits a given floorplan to them) and the small
// helpers both use. Floorplan coordinates: Vec2 (x, z).

#include "room_estimation.h"

#include <string>
#include <utility>
#include <vector>

namespace roomprobe::room_planes {

inline constexpr double PI = 3.14159265358979323846;
inline constexpr double DEG = PI / 180.0;
inline constexpr double BIN_M = 0.01; // the histograms of plane offsets and heights

std::string format(const char *p_format, double p_a, double p_b = 0.0, double p_c = 0.0);
double wrap_angle(double p_angle); // to (-pi, pi]

// Weighted samples along a line (plane offsets, heights): a histogram of BIN_M bins and the sums
// over a window of +-p_half_m around each bin.
struct LineHistogram {
	double start = 0.0;
	std::vector<double> window; // area within +-half of each bin's centre

	LineHistogram(const std::vector<std::pair<double, double>> &p_values, double p_half_m);
	double centre(size_t p_bin) const { return start + (double(p_bin) + 0.5) * BIN_M; }
	// The bin of the largest window within +-p_radius_m of p_bin.
	size_t local_peak(size_t p_bin, double p_radius_m) const;
};

// The weighted mean of the values within p_half_m of p_centre (the plane's refined offset). A
// histogram peak's bin may sit at the edge of its window (an exact plane fills one bin, and every
// window holding it ties), so callers take the mean within twice the tolerance first.
double mean_near(const std::vector<std::pair<double, double>> &p_values, double p_centre, double p_half_m, double *r_rms = nullptr, double *r_weight = nullptr);
// The value below which p_share of the weight lies.
double weighted_quantile(std::vector<std::pair<double, double>> p_values, double p_share);

// A vertical surface sample in the floor plane's 2-D coordinates.
struct FlatSample {
	Vec2 position, normal; // normal unit, horizontal
	double area_m2 = 0.0;
	double angle = 0.0; // of the normal
};

inline Vec2 perp(const Vec2 &p_v) { return { -p_v.y, p_v.x }; }
inline double dot2(const Vec2 &p_a, const Vec2 &p_b) { return p_a.x * p_b.x + p_a.y * p_b.y; }
Vec2 from_angle(double p_angle);

// The normal directions walls take: histogram peaks of the vertical samples' normal angles, snapped
// to the dominant axis's multiples of 90 degrees when within manhattan_snap_deg. r_axis: the
// dominant direction; r_manhattan: every direction was snapped.
// p_axis_correction: added to the normals' axis before snapping (the walls' lines measure the axis
// better than the normals do; room_estimation.cpp).
std::vector<double> wall_directions(const std::vector<FlatSample> &p_flat, const RoomEstimationOptions &p_options, double *r_axis, bool *r_manhattan,
		double p_axis_correction = 0.0);
// The vertical planes along one normal direction: offset peaks with enough area seen and wide enough.
std::vector<WallEstimate> walls_along(const std::vector<FlatSample> &p_flat, double p_direction, const RoomEstimationOptions &p_options);
// A partition's two faces lie back to back at most this far apart.
inline constexpr double PARTITION_MAX_THICKNESS_M = 0.3;
// The walls among vertical planes: where several face the same way over the same stretch, the
// outermost (a table's side or a wardrobe's front stands in front of the wall behind it), except
// a plane with its own back close behind it: a partition, whatever stands beyond it.
std::vector<WallEstimate> keep_outermost(const std::vector<WallEstimate> &p_candidates);
// Every wall of every direction (keep_outermost of walls_along).
std::vector<WallEstimate> find_walls(const std::vector<FlatSample> &p_flat, const RoomEstimationOptions &p_options, double *r_axis, bool *r_manhattan,
		double p_axis_correction = 0.0);

} // namespace roomprobe::room_planes
