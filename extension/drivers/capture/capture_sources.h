#pragma once
// The rig's live devices as capture sources (device_capture.h): each wraps one driver and turns
// its frames into the frames the engine takes (recording/recording_types.h).
//   RGB-D: OpenNI2 (Xtion, Orbbec, Kinect-class cameras; or an .oni file played as if live).
//   Fisheye: Aravis (GigE Vision, USB3 Vision: the paper's Chameleon3), or a UVC webcam through
//     OpenCV's VideoCapture (V4L2; a video file plays as if live, for tests).
// A source checks every frame against the rig's image size, so a camera in the wrong mode is a
// clear reason in its state, not a frame the engine refuses later.

#include "device_capture.h"

#include <limits>
#include <memory>
#include <string>

namespace roomprobe::drivers {

struct RgbdSourceSettings {
	std::string uri; // an OpenNI2 URI or an .oni path; empty: the first device OpenNI2 lists
	int width = 640; // the rig's RGB (and registered depth) size; 0: take what comes
	int height = 480;
};

struct FisheyeSourceSettings {
	std::string device; // Aravis: a device id or IP; UVC: /dev/videoN, N, or a video file. Empty: the first found
	int width = 0; // the rig's fisheye size; 0: take what comes
	int height = 0;
	std::string pixel_format; // Aravis: a GenICam name to set ("BayerRG8"); empty: the camera's own
	bool auto_exposure = true; // off: exposure_us and gain below are set (NaN: left as they are)
	double exposure_us = std::numeric_limits<double>::quiet_NaN();
	double gain = std::numeric_limits<double>::quiet_NaN();
	bool include_fake = false; // Aravis: the first-found search may pick Aravis' Fake camera (tests)
};

// Empty when a frame of p_width x p_height has the rig's size (p_rig_*; both 0: any), else why
// not, naming the device (p_name) and the stream (p_what: "RGB-D", "fisheye").
std::string check_size(const std::string &p_name, const char *p_what, int p_width, int p_height, int p_rig_width, int p_rig_height);

std::unique_ptr<CaptureSource> make_openni2_rgbd_source(const RgbdSourceSettings &p_settings);
std::unique_ptr<CaptureSource> make_aravis_fisheye_source(const FisheyeSourceSettings &p_settings);
std::unique_ptr<CaptureSource> make_uvc_fisheye_source(const FisheyeSourceSettings &p_settings);

} // namespace roomprobe::drivers
