#pragma once
// How wrong a mirror sphere looks (issue #16, distance-aware reflections): a virtual mirror sphere
// centred at a map's centre, seen from a few viewers, against a ray-traced reference. The
// reference is the true scene's radiance along each reflected ray, from its point on the sphere
// (synth/synth_renderer.h, the renderer that made the recording); the estimates read the map
// along the reflected direction (what mirror.gdshader did before), and along
// envmap/parallax.h's distance-aware direction.

#include <envmap/cubemap.h>
#include <synth/synth_renderer.h>

namespace roomprobe {

struct MirrorScores {
	int views = 0; // viewers with a clear line of sight to the sphere
	size_t pixels = 0; // sphere pixels scored, all views together
	double psnr_plain_db = 0.0; // tone-mapped PSNR over the sphere's pixels, the map read along r
	double psnr_parallax_db = 0.0; // the same, read along parallax_direction
};

// The sphere of radius p_radius_m about p_map's centre p_centre, at time p_time_s, seen from up to
// four viewers 1.5 m away horizontally (+X, -X, +Z, -Z of the centre; those whose line of sight
// the scene blocks are left out), each a p_image_size-square pinhole image framing the sphere.
MirrorScores mirror_sphere_error(const synth::SynthRenderer &p_scene, const Cubemap &p_map, const glm::dvec3 &p_centre, double p_radius_m, double p_time_s,
		int p_image_size = 96);

} // namespace roomprobe
