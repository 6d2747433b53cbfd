#pragma once
// The coarse model's texture from the RGB camera too (issue #16, beyond the paper's §4.3): the
// paper's upward fisheye never sees the floor and the lower walls, which the inpainting then
// fills with one smeared colour, while the hand-held RGB-D camera looks at exactly those. Every
// texel the fisheye has never observed is projected into the RGB image (camera/pinhole_camera.h)
// and taken from it where the registered depth says the camera sees that very texel (its depth
// along the optical axis within a tolerance of the measured one: furniture in front of the wall
// hides it, and a texel beyond the depth range is not taken on trust).
//
// Fisheye observations stay first: an RGB value fills a texel only while no fisheye observation
// is held (CoarseTexture::quality == 0), and the next fisheye observation replaces it (its
// quality beats 0). Between RGB views the best is kept, by RgbTextureOptions' quality
// (cos_view / distance^2), in CoarseTexture::rgb_quality. The RGB camera's 8-bit values go to the
// texture's units through the rig's photometry (rig/photometry.h rgb_radiance_lut, the dense
// colours' own conversion); clipped pixels (255) are not taken.

#include <io/opencv.h>

#include "coarse_texture.h"
#include "texture_update.h"

#include <camera/camera_params.h>
#include <math/pose.h>
#include <rig/photometry.h>

namespace roomprobe {

struct RgbTextureOptions {
	// Visible when |measured depth - texel depth| <= max(depth_tolerance_m, depth_tolerance_fraction
	// * texel depth): the depth camera's noise grows with distance. Metres, and unitless.
	double depth_tolerance_m = 0.04;
	double depth_tolerance_fraction = 0.03;
	// Texels seen more obliquely than this (cos between the inward normal and the direction to the
	// camera) are not taken: unitless, in [0, 1).
	double min_cos_view = 0.25;
	// Nearer than this does not count as better, metres; > 0.
	double min_distance_m = 0.5;
	// A new view replaces the kept one when its quality >= kept * (1 - replace_epsilon); unitless,
	// in [0, 1) (as TextureUpdateOptions'). Larger than the fisheye's: an RGB value is nobody
	// else's to refresh (the inpainting follows the light, and the fisheye never sees it).
	double replace_epsilon = 0.5;
	// Pixels this close to the image border are not sampled; >= 0.
	double border_px = 1.0;
};

struct RgbTextureStats {
	size_t texels_visible = 0; // unobserved-by-fisheye texels the RGB camera sees (in view, depth agrees)
	size_t texels_updated = 0; // of those, how many took the new view
};

// Updates io_texture from one RGB-D frame: p_rgb CV_8UC3 (R, G, B) and p_depth_m CV_32FC1
// (metres along the optical axis, NaN: no reading), both p_camera's size, taken at
// p_world_from_rgb (room frame). p_lut: the RGB camera's value -> radiance (null: value / 255).
// r_updated (optional, CV_8UC1 atlas-sized, not cleared): 255 on each texel that took the view, so
// that the next lighting change (§4.6) is not applied again to a value of the present lighting.
// r_pairs (optional): the lighting estimate's pairs (§4.6; its step is read, its rows filled) of
// the texels this view sees that already hold an RGB value: (held, this view's), before the
// update writes; clipped samples left out. Without a fisheye these are the only pairs (issue #43).
// Parallel over atlas rows. Zero stats when the inputs do not fit together.
RgbTextureStats update_coarse_texture_from_rgb(const TexelGeometry &p_geometry, const PinholeParams &p_camera, const Pose &p_world_from_rgb,
		const cv::Mat &p_rgb, const cv::Mat &p_depth_m, const ResponseCurve *p_lut, CoarseTexture *io_texture,
		const RgbTextureOptions &p_options = RgbTextureOptions(), cv::Mat *r_updated = nullptr, LightingPairs *r_pairs = nullptr);

} // namespace roomprobe
