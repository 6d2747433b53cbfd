#pragma once
// What a probe's map draws over the room once the room is rendered (paper §4.7, last paragraph):
// the other virtual objects. An interface here so that the map's renderer (probe_renderer.h) needs
// nothing above envmap; prt/virtual_objects.h's VirtualScene is the one implementation.

#include "cubemap.h"
#include "spherical_harmonics.h"

#include <glm/vec3.hpp>

#include <cstddef>

namespace roomprobe {

struct VirtualDrawStats {
	size_t texels_traced = 0, texels_drawn = 0, texels_shadowed = 0;
	double milliseconds = 0.0;
};

class MapOverlay {
public:
	virtual ~MapOverlay() = default;
	virtual size_t object_count() const = 0;
	// Draws over io_map as seen from p_position_m, lit by p_light (SH) and, for mirrors and glass,
	// by p_previous (the probe's previous map; null: none yet).
	virtual VirtualDrawStats draw(const glm::dvec3 &p_position_m, const ShCoefficients &p_light, const Cubemap *p_previous, Cubemap *io_map) const = 0;
};

} // namespace roomprobe
