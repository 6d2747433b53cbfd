#pragma once
// Internal to the room module: step 2 of room_estimation.h, the room's polygon from the walls'
// lines, cut into faces by segment_arrangement.h and joined where the sweep saw floor.

#include "room_estimation.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace roomprobe::room_planes {

// Where the floor was seen, on a grid in the floor plane's 2-D coordinates.
struct FloorGrid {
	Vec2 origin;
	double cell = 0.05;
	int width = 0, height = 0;
	std::vector<uint8_t> seen;
	bool at(const Vec2 &p_point) const {
		const int x = int(std::floor((p_point.x - origin.x) / cell)), y = int(std::floor((p_point.y - origin.y) / cell));
		return x >= 0 && y >= 0 && x < width && y < height && seen[size_t(y) * size_t(width) + size_t(x)] != 0;
	}
};

// The share of the segment a to b covered by a wall on its line facing its left side (or its
// right, when p_left is false): what the sweep saw there as a wall, seen from that side.
double wall_cover(const Vec2 &p_a, const Vec2 &p_b, bool p_left, const std::vector<WallEstimate> &p_walls);

// The room's polygon: the walls' lines and the ends of what was seen of them cut the floor into
// faces; the faces whose floor was seen are joined, and the largest region's boundary is the
// room, counter-clockwise. Empty when no bounded region was seen.
std::vector<Vec2> room_polygon(const std::vector<WallEstimate> &p_walls, const FloorGrid &p_grid, const std::vector<Vec2> &p_cameras,
		const RoomEstimationOptions &p_options);

} // namespace roomprobe::room_planes
