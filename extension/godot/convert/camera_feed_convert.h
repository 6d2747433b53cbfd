#pragma once
// A Godot camera feed's newest frame as an 8-bit image for the engine (issue #43). Godot's feeds
// (CameraServer: V4L2 webcams on Linux, Android's cameras, a headset's passthrough) hand their
// frames to the renderer only, as RGB, YUY2 or separate Y and CbCr textures; the reader
// reads them back on the main thread and makes R, G, B (or grey) of them, as Godot's own camera
// background does.

#include <opencv2/core/mat.hpp>

#include <rp_godot/godot.h>

#include <string>

namespace roomprobe {

class CameraFeedReader {
public:
	// Main thread. CV_8UC3 (R, G, B) or CV_8UC1 (a grey feed); empty, with r_error saying why,
	// when the feed has no readable frame (none yet, an external GPU texture, a renderer that
	// keeps no copy).
	cv::Mat read(const godot::Ref<godot::CameraFeed> &p_feed, std::string *r_error);
	void reset(); // forgets the feed's textures (another feed, or none)

private:
	godot::Ref<godot::Image> texture_image(int64_t p_feed_id, godot::CameraServer::FeedImage p_which);

	int64_t feed_id = -1;
	// By CameraServer::FeedImage: FEED_RGBA_IMAGE, FEED_YCBCR_IMAGE and FEED_Y_IMAGE are all 0
	// (one texture), FEED_CBCR_IMAGE is 1.
	godot::Ref<godot::CameraTexture> textures[2];
};

} // namespace roomprobe
