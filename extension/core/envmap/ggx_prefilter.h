#pragma once
// GGX-prefiltered environment maps for rough materials (paper §4.8; the split-sum approximation,
// Karis 2013): a chain of cubemaps, level k for perceptual roughness r_k = k / (levels - 1),
// GGX alpha = r^2 (the convention of Godot's BaseMaterial3D). With the normal and the view both
// along the reflection R, level k holds
//
//   F(R) = integral of L(l) D(h) max(0, R . l) dl / integral of D(h) max(0, R . l) dl,
//   h = normalize(R + l),
//
// estimated with GGX importance sampling (Hammersley points, h drawn from D(h)(n . h)) and
// filtered importance sampling (Krivanek and Colbert 2008): each sample reads a box-filtered
// level of the source whose texels are about the sample's share of the lobe, so few samples give
// a smooth map. Level 0 is the source itself (a mirror); level k's faces are the source's size
// over 2^k (at least 1).

#include "cubemap.h"

#include <vector>

namespace roomprobe {

struct GgxPrefilterOptions {
	int levels = 6; // >= 1
	// A texel, >= 1. Against a brute-force convolution of a map with a small light of radiance 20
	// (tests/core/test_envmap_ggx.cpp): 1.5 to 3 % relative RMS at 1024, 5 to 9 % at 256, about
	// 15 to 23 % at 64; the cost is levels' texels x samples (not yet on the probe worker).
	int samples = 1024;
};

// The roughness level p_level of a p_levels chain stands for.
double ggx_level_roughness(int p_level, int p_levels);

// An empty vector for an invalid source or options.
std::vector<Cubemap> prefilter_ggx(const Cubemap &p_source, const GgxPrefilterOptions &p_options = GgxPrefilterOptions());

// The same integral by brute force over every source texel (exact up to the source's texels):
// the reference the tests hold prefilter_ggx to. Slow: p_size^2 x 6 x source texels.
Cubemap ggx_reference(const Cubemap &p_source, double p_roughness, int p_size);

} // namespace roomprobe
