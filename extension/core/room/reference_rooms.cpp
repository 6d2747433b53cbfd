#include "reference_rooms.h"

namespace roomprobe {

Floorplan figure4_two_rooms() {
	constexpr double partition_half_m = 0.06;
	constexpr double partition_x_m = 4.0;
	constexpr double partition_depth_m = 3.0;
	Floorplan floorplan;
	floorplan.points = {
		{ 0.0, 0.0 },
		{ partition_x_m - partition_half_m, 0.0 },
		{ partition_x_m - partition_half_m, partition_depth_m },
		{ partition_x_m + partition_half_m, partition_depth_m },
		{ partition_x_m + partition_half_m, 0.0 },
		{ 8.0, 0.0 },
		{ 8.0, 4.5 },
		{ 0.0, 4.5 },
	};
	floorplan.ceiling_height_m = 2.6;
	return floorplan;
}

Floorplan living_room() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 5.0, 0.0 }, { 5.0, 4.0 }, { 0.0, 4.0 } };
	floorplan.ceiling_height_m = 2.5;
	return floorplan;
}

Floorplan l_shaped_room() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 6.0, 0.0 }, { 6.0, 3.0 }, { 3.0, 3.0 }, { 3.0, 5.0 }, { 0.0, 5.0 } };
	floorplan.ceiling_height_m = 2.4;
	return floorplan;
}

} // namespace roomprobe
