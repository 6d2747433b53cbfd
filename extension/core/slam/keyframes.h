#pragma once
// Keyframes for relocalising from anywhere the model covers (issue #41): the held pose's
// neighbourhood is not enough when the camera was carried elsewhere while lost (put down and
// picked up again across the room). Dense SLAM keeps a keyframe whenever a trusted frame is far
// from every keyframe so far (KeyframeOptions), as a small thumbnail of its depth and intensity
// (InfiniTAM's relocaliser keeps such thumbnails too, encoded by random ferns; here they are
// compared directly, which stays cheap for the few hundred keyframes a room holds). A lost frame's
// thumbnail ranks the keyframes, and dense SLAM verifies the best few geometrically (ICP against
// the model seen from each keyframe's pose, dense_slam.h) before it accepts one.

#include "slam_types.h"

#include <io/opencv.h>

#include <cstddef>
#include <vector>

namespace roomprobe {

struct KeyframeOptions {
	double min_distance_m = 0.2; // a trusted frame is kept when this far from every keyframe's position,
	double min_angle_deg = 20.0; // or turned this far from the nearest one's view direction
	int max_keyframes = 2000; // beyond it no more are kept (about 10 KiB each)
	int thumbnail_width = 40, thumbnail_height = 30; // pixels; each averages a block of the frame
	// Thumbnails whose readings overlap on fewer than this share of their pixels are not compared.
	double min_overlap = 0.3;
	// The depth difference that weighs as much as one standard deviation of intensity, metres.
	double depth_scale_m = 0.1;
};

// A frame in small: block means of its depth (metres, 0 where a block has no reading) and of its
// intensity, the latter normalised to zero mean and unit deviation over the blocks with readings,
// so that a change of exposure or of the room's light does not move it.
struct KeyframeThumbnail {
	cv::Mat depth_m; // CV_32FC1
	cv::Mat intensity; // CV_32FC1, 0 where the depth has none
	bool usable = false; // enough blocks with readings to compare
};

struct Keyframe {
	int id = 0; // 0, 1, ... in the order kept
	Pose world_from_camera;
	KeyframeThumbnail thumbnail;
};

class KeyframeDatabase {
public:
	explicit KeyframeDatabase(const KeyframeOptions &p_options = KeyframeOptions()) :
			opts(p_options) {}

	// p_depth_m: clean depth (NaN where none), p_rgb: CV_8UC3 (may be empty: depth alone).
	KeyframeThumbnail thumbnail(const cv::Mat &p_depth_m, const cv::Mat &p_rgb) const;
	// Whether a frame at p_world_from_camera would be kept: far from every keyframe (options).
	bool wants(const Pose &p_world_from_camera) const;
	// Keeps the frame as a keyframe when wants() says so; true when it did.
	bool consider(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_world_from_camera);
	// The indices of the p_count keyframes whose thumbnails are nearest p_query's, nearest first
	// (those that cannot be compared are left out).
	std::vector<size_t> nearest(const KeyframeThumbnail &p_query, size_t p_count) const;
	// The thumbnails' distance (about 0 for the same view, 1 and more for others); negative when
	// they overlap too little to say.
	double distance(const KeyframeThumbnail &p_a, const KeyframeThumbnail &p_b) const;

	size_t size() const { return frames.size(); }
	const Keyframe &at(size_t p_index) const { return frames[p_index]; }
	void clear() { frames.clear(); }
	const KeyframeOptions &options() const { return opts; }

private:
	KeyframeOptions opts;
	std::vector<Keyframe> frames;
};

} // namespace roomprobe
