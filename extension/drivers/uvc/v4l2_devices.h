#pragma once
// UVC webcams (the cheap USB fisheye) as V4L2 lists them: /dev/video* nodes that capture video,
// with their pixel formats and frame sizes. Streaming goes through OpenCV's VideoCapture
// (capture/capture_sources.h); this only lists, with V4L2's own ioctls.

#include "../device_types.h"

#include <vector>

namespace roomprobe::drivers {

// Capture nodes (backend "v4l2", id "/dev/videoN", model: the card's name, vendor: its driver),
// each with its modes ("MJPG 1280x720", "YUYV 640x480"). No node: an empty list.
std::vector<DeviceInfo> list_v4l2_devices();

} // namespace roomprobe::drivers
