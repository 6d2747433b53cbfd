#pragma once

// Sample rooms shared by tests, demos and synthetic scenes. All are returned
// normalized (counter-clockwise in the (x, z) plane, see floorplan.h).

#include "floorplan.h"

namespace roomprobe {

// The paper's Figure 4: two rooms partly separated by a partition. Outer
// rectangle 8 m (x) by 4.5 m (z); a 0.12 m thick partition centred on x = 4 m
// hangs from the z = 0 wall 3 m into the room. 8 corners, non-convex.
// Ceiling 2.6 m. Area 35.64 m^2, perimeter 31 m.
Floorplan figure4_two_rooms();

// A convex 5 m (x) by 4 m (z) rectangle with a 2.5 m ceiling. Area 20 m^2, perimeter 18 m.
Floorplan living_room();

// An L-shaped room: a 6 m by 3 m wing along x plus a 3 m by 2 m wing along z
// (6 corners, one reflex at (3, 3)). Ceiling 2.4 m. Area 24 m^2, perimeter 22 m.
Floorplan l_shaped_room();

} // namespace roomprobe
