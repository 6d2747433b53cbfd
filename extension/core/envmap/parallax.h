#pragma once
// Distance-aware reflections (issue #16): the paper's future work [52], behind the bright band at
// the rim of its Figure 11's sphere. A map rendered at its centre c is right only for rays that
// start at c. A mirror at point p reflecting along r sees the surface where p + t r meets the
// room; from c that surface lies along p + t r - c, not along r, and the nearer the surface and
// the farther p from c, the larger the difference.
//
// The map's distances (Cubemap::distance_m, metres from c to the surface each texel shows: the
// coarse prism and the dense model) give that surface as the root of
//   f(t) = D(towards p + t r - c) - |p + t r - c|,
// positive before the surface and negative beyond it (as in distance impostors: Szirmay-Kalos,
// Aszodi, Lazanyi, Premecz, "Approximate ray-tracing on the GPU with distance impostors",
// Eurographics 2005). The first guess is where the ray leaves the sphere of radius D(r) about c
// (exact in a spherical room; D(r) where that is no guess), doubled up to PARALLAX_EXPANSIONS times until f < 0; then
// PARALLAX_ITERATIONS steps of regula falsi (Illinois) within that bracket. A plain fixed-point
// iteration on the spheres was tried first: on a mirror 30 cm from a wall it left a mean error of
// 4 degrees after 4 steps.
//
// shaders/parallax.gdshaderinc runs the same steps on the GPU for mirror.gdshader and
// glass.gdshader, reading the distances from the map's alpha (LiveRoom's gpu faces; filtered
// across face seams and in half floats there, bilinear within a face here).
// tests/core/test_envmap_parallax.cpp checks these steps against the exact hits in a box room,
// tests/godot/test_rendering_room_probe.gd the shader against rays traced by hand in the same room.

#include "cubemap.h"

#include <glm/vec3.hpp>

namespace roomprobe {

inline constexpr int PARALLAX_ITERATIONS = 6;
inline constexpr int PARALLAX_EXPANSIONS = 3;

// The map's distance along p_direction (non-zero): a bilinear read of distance_m, as the GPU's
// linear filter reads the alpha. 0 where the map has no distances.
double sample_distance(const Cubemap &p_map, const glm::dvec3 &p_direction);

// The direction to read p_map along for the ray p_point + t p_direction (p_direction non-zero),
// p_map rendered at p_centre. p_direction itself where the map has no distances, or where the
// distance along it is 0 (nothing there) or leaves p_point outside the surface.
glm::dvec3 parallax_direction(const Cubemap &p_map, const glm::dvec3 &p_centre, const glm::dvec3 &p_point, const glm::dvec3 &p_direction,
		int p_iterations = PARALLAX_ITERATIONS);

} // namespace roomprobe
