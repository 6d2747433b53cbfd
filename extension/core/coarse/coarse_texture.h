#pragma once
// The coarse model's texture (paper §4.1, §4.3-§4.6): one atlas over the room mesh's charts
// (room/room_mesh.h), with the masks the later stages need. Plain data.

#include <room/room_mesh.h>

#include <io/opencv.h>

namespace roomprobe {

struct CoarseTexture {
	// CV_32FC3, linear R, G, B, in the fisheye image's units (8-bit frames: value / 255, so 1.0
	// is the brightest an 8-bit fisheye records; HDR frames: their radiance). Size: the atlas's.
	cv::Mat color;
	// CV_8UC1: 255 where the texel has been observed by the fisheye at least once (§4.5's
	// inpainting mask: only texels never observed are inpainted).
	cv::Mat observed;
	// CV_32FC1: the quality of the observation each texel holds (§4.3, "keep the best"), 0 for none.
	cv::Mat quality;
	// CV_8UC1: 255 where the latest fisheye frame updated the texel (§4.6 adds the lighting
	// change to the others).
	cv::Mat updated;
	// CV_8UC1: 255 where the value held was clipped in its frame (a lower bound of the radiance;
	// coarse/texture_update.h lets any unclipped observation replace it).
	cv::Mat saturated;
	// CV_32FC1: where the texel holds a value from the RGB camera (never seen by the fisheye:
	// quality == 0), the best RGB view's quality (coarse/rgb_texture_update.h); 0 elsewhere.
	cv::Mat rgb_quality;
};

// An empty texture for p_mesh's atlas: black, nothing observed.
CoarseTexture make_coarse_texture(const RoomMesh &p_mesh);

} // namespace roomprobe
