#pragma once
// The paper's baseline environment map (§5.3), without the coarse model: each fisheye frame is
// rendered into the probe's cubemap after applying a rotation from the fisheye's current pose,
// ignoring the translation between probe and camera (the environment is assumed distant). The
// cubemap is not cleared between frames, so it builds up as more of the room is observed: a
// texel keeps the value of the latest frame that saw it.

#include "cubemap.h"

#include <camera/camera_params.h>
#include <math/pose.h>

namespace roomprobe {

class BaselineEnvmap {
public:
	// An empty (black, nothing seen) p_size cubemap. Its position does not matter: the baseline
	// ignores translation.
	explicit BaselineEnvmap(int p_size = 256);

	// Renders one fisheye frame in: for every face pixel direction d (world), the fisheye-frame
	// direction rotation^-1 d (world_from_fisheye's rotation only) is projected with
	// project_omni; where that lands inside the image and its circle (omni_pixel_valid) the
	// image is sampled bilinearly and overwrites the texel. p_image: CV_8UC1 or CV_8UC3 (R, G, B;
	// value / 255, the coarse texture's units) or CV_32FC3 linear R, G, B (as is). Returns the
	// number of texels written; 0 for an image of another type or not p_params' size.
	// Parallel over face rows (TBB).
	int add_frame(const cv::Mat &p_image, const OmniParams &p_params, const Pose &p_world_from_fisheye);

	const Cubemap &cubemap() const { return map; }
	// CV_8UC1 per face: 255 where some frame has written the texel, 0 where never seen.
	const CubemapFaces &seen() const { return seen_mask; }
	// Fraction of the sphere's solid angle seen so far, 0..1.
	double seen_fraction() const;
	// Back to black and nothing seen.
	void clear();

private:
	Cubemap map;
	CubemapFaces seen_mask;
};

} // namespace roomprobe
