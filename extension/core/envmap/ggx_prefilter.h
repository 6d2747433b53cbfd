#pragma once
// GGX-prefiltered environment maps for rough materials (paper §4.8; the split-sum approximation,
// Karis 2013): a chain of cubemaps, level k of L for perceptual roughness r_k = (k / (L - 1))^2
// and GGX alpha = r^2. That is Godot's convention: its scene shader reads a radiance map at
// lod = sqrt(roughness) * (L - 1), so a shader that reads RoomProbe's chain the same way agrees
// with a StandardMaterial3D of the same roughness. With the normal and the view both along the
// reflection R, level k holds
//
//   F(R) = integral of L(l) D(h) max(0, R . l) dl / integral of D(h) max(0, R . l) dl,
//   h = normalize(R + l),
//
// estimated with GGX importance sampling (Hammersley points, h drawn from D(h)(n . h)) and
// filtered importance sampling (Krivanek and Colbert 2008): each sample reads a box-filtered
// level of the source whose texels are about the sample's share of the lobe, so few samples give
// a smooth map. Level 0 is the source itself (a mirror); level k's faces are the source's size
// over 2^k.
//
// The filter is linear in the source and its weights depend only on the face size, so GgxFilter
// works them out once (which source texels, with which weights, make each output texel) and a
// map is then one weighted sum per texel: cheap enough for the probe worker's every map.

#include "cubemap.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace roomprobe {

struct GgxPrefilterOptions {
	// Levels of the chain, >= 1; 0 picks faces down to 4 x 4 (ggx_default_levels).
	int levels = 0;
	// A texel, >= 1. Against a brute-force convolution of a map with a small light of radiance 20
	// (tests/core/test_envmap_ggx.cpp): 5.3 / 4.8 / 8.1 % relative RMS at roughness 0.25 / 0.56 /
	// 1 with 256 samples; 5.4 / 1.5 / 2.7 % with 1024. More samples cost the one-off build and
	// memory: at 256^2 faces, 256 samples make 8.3 M taps (64 MiB), built in 2.8 s on two cores
	// (./roomprobe bench ... --probe-size 256 prints it); a quarter of that at 128^2.
	int samples = 256;
};

// The roughness level p_level of a p_levels chain stands for: (p_level / (p_levels - 1))^2.
double ggx_level_roughness(int p_level, int p_levels);
// The levels RoomProbe's maps carry: faces from p_size down to 4 x 4 (1 for sizes under 8).
// Shaders find it from the texture's size: log2(size) - 1.
int ggx_default_levels(int p_size);

// The precomputed filter for one face size.
class GgxFilter {
public:
	GgxFilter() = default;
	// Empty (is_valid() false) for a size < 1 or invalid options.
	GgxFilter(int p_size, const GgxPrefilterOptions &p_options = GgxPrefilterOptions());

	bool is_valid() const { return size > 0; }
	int face_size() const { return size; }
	int level_count() const { return int(levels.size()) + 1; }
	int sample_count() const { return samples; }
	size_t tap_count() const; // weights stored, all levels
	size_t memory_bytes() const;

	// The chain of a source of face_size(): level 0 is the source itself (sharing its pixels, as a
	// Cubemap's copy does). Empty for another size or an invalid source.
	std::vector<Cubemap> apply(const Cubemap &p_source) const;
	// The same after a change of some source faces: p_previous is this filter's chain of a source
	// that differs from p_source only in the faces of p_changed_faces (a bit per face, 1 << face).
	// Texels whose taps read none of them are copied from p_previous (the filter is linear, so they
	// come out the same). r_changed_faces (may be null): a bit per output face some level of which
	// was computed again. A p_previous of another shape is ignored (everything computed again).
	std::vector<Cubemap> apply(const Cubemap &p_source, const std::vector<Cubemap> &p_previous, uint8_t p_changed_faces, uint8_t *r_changed_faces) const;

	// Texels of the box pyramid the taps index: every box level of the source, flattened.
	size_t pyramid_texels() const { return pyramid_offset.empty() ? 0 : pyramid_offset.back() + 6; }
	// That pyramid of p_source (face_size()), in the order the taps index it.
	std::vector<cv::Vec3f> box_pyramid(const Cubemap &p_source) const;

private:
	friend class GgxFilterGpu; // uploads the levels' taps (ggx_prefilter_gpu.h)
	struct Level {
		int size = 0;
		std::vector<uint32_t> first; // per output texel (face, y, x) and one past the end: its taps
		std::vector<uint32_t> texel; // into the flattened box pyramid
		std::vector<float> weight; // summing to 1 per output texel
		std::vector<uint8_t> source_faces; // per output texel: a bit per source face its taps read
	};
	int size = 0, samples = 0;
	std::vector<size_t> pyramid_offset; // first texel of each box level in the flattened pyramid
	std::vector<Level> levels; // levels 1 .. L - 1
};

// The default filter for p_size from a process-wide cache (every engine shares it). Up to 64^2
// faces it is built at once (under 0.2 s); larger ones on a background thread that the first call
// starts (about 3 s at 256^2 on two cores), and until it is done the call returns null, or
// waits with p_wait.
std::shared_ptr<const GgxFilter> shared_ggx_filter(int p_size, bool p_wait = false);

// GgxFilter(p_source.size, p_options).apply(p_source); an empty vector for an invalid source or
// options.
std::vector<Cubemap> prefilter_ggx(const Cubemap &p_source, const GgxPrefilterOptions &p_options = GgxPrefilterOptions());

// The same integral by brute force over every source texel (exact up to the source's texels):
// the reference the tests hold prefilter_ggx to. Slow: p_size^2 x 6 x source texels.
Cubemap ggx_reference(const Cubemap &p_source, double p_roughness, int p_size);

} // namespace roomprobe
