#pragma once

// The ground floor's frames: an RGB-D frame and a fisheye frame as every stage takes them (SLAM,
// the coarse model, the recorder, the engine), with what a live device said about each. The
// drivers convert their devices' frames into these at their edge (drivers/capture).

#include <opencv2/core/mat.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

namespace roomprobe {

// What a live device said about one of its frames, kept in recordings made live (capture.txt,
// docs/recording-format.md). Unknown values are NaN (times, exposure, gain) or -1 (frame id).
struct CaptureInfo {
	double device_time_s = std::numeric_limits<double>::quiet_NaN(); // the device's own clock, seconds
	int64_t device_frame_id = -1; // the device's frame counter (a jump: frames the device dropped)
	// The fisheye's exposure time (microseconds) and gain (the camera's unit, usually dB) when
	// the frame was taken: what a photometric model needs to bring frames to one radiance scale
	// (rig/photometry.h exposure_ratio).
	double exposure_us = std::numeric_limits<double>::quiet_NaN();
	double gain = std::numeric_limits<double>::quiet_NaN();
	bool is_known() const { // any value known
		return !std::isnan(device_time_s) || device_frame_id >= 0 || !std::isnan(exposure_us) || !std::isnan(gain);
	}
};

// An RGB image and the depth image registered to it (one RGB-D frame).
struct RgbdFrame {
	double timestamp_s = 0.0; // the RGB image's timestamp, seconds on the RGB-D clock
	// The depth image's timestamp, seconds on the RGB-D clock. NaN when writing means "the same
	// as timestamp_s"; a reader always fills it in.
	double depth_timestamp_s = std::numeric_limits<double>::quiet_NaN();
	cv::Mat rgb; // CV_8UC3 in R, G, B order (not OpenCV's usual BGR), the rig's rgb size
	// CV_32FC1, metres along the optical axis (z, not ray length), NaN where there is no reading;
	// registered to rgb (same size, same pixels). The writer also takes CV_16UC1 holding the
	// raw values already in units of Rig::depth_scale_m (0 = no reading).
	cv::Mat depth_m;
	CaptureInfo capture; // live frames only (exposure and gain stay unknown)
};

// One image of the upward fisheye.
struct FisheyeFrame {
	double timestamp_s = 0.0; // seconds on the fisheye's own clock
	// 8-bit: CV_8UC1 (gray) or CV_8UC3 (R, G, B order); HDR: CV_32FC3 linear R, G, B.
	// The rig's fisheye size.
	cv::Mat image;
	bool hdr = false; // true exactly when image is CV_32FC3 (stored as EXR)
	// CV_8UC1, 255 where a channel was clipped: set on a linearised 8-bit frame (rig/photometry.h),
	// which the coarse texture reads; empty otherwise (never stored).
	cv::Mat saturated;
	CaptureInfo capture; // live frames and synthetic ones with their exposure
};

} // namespace roomprobe
