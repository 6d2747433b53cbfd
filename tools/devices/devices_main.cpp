// roomprobe_devices: what the rig could capture from, with the modes each device offers.
//   OpenNI2 depth cameras (Xtion, Orbbec, Kinect-class), Aravis machine-vision cameras (GigE Vision,
//   USB3 Vision) and V4L2 capture nodes (UVC webcams).
// usage: roomprobe_devices [--fake]   (--fake lists Aravis' built-in Fake camera too)
// The last line is a summary: openni2=N aravis=N v4l2=N.

#include "aravis/aravis_camera.h"
#include "openni2/openni2_device.h"
#include "uvc/v4l2_devices.h"

#include <cstdio>
#include <cstring>
#include <string>
#include "../common/cli.h"

using namespace roomprobe::drivers;

namespace {

void print_device(const DeviceInfo &p_info) {
	std::printf("  %s  (%s %s%s%s)\n", p_info.id.c_str(), p_info.vendor.c_str(), p_info.model.c_str(),
			p_info.serial.empty() ? "" : ", ", p_info.serial.c_str());
	for (const std::string &mode : p_info.modes) {
		std::printf("      %s\n", mode.c_str());
	}
}

int run(int p_argc, char **p_argv) {
	bool fake = false;
	for (int i = 1; i < p_argc; i++) {
		if (std::strcmp(p_argv[i], "--fake") == 0) {
			fake = true;
		} else {
			std::fprintf(stderr, "roomprobe_devices: unknown argument '%s' (usage: roomprobe_devices [--fake])\n", p_argv[i]);
			return 2;
		}
	}

	std::printf("RGB-D cameras (OpenNI2):\n");
	size_t openni2 = 0;
	DriverResult<std::vector<DeviceInfo>> listed = list_openni2_devices();
	if (!listed.ok()) {
		std::printf("  (OpenNI2 cannot list: %s)\n", listed.error.c_str());
	} else {
		for (DeviceInfo &info : listed.value) {
			DriverResult<std::vector<std::string>> modes = list_openni2_modes(info.id);
			info.modes = modes.ok() ? modes.value : std::vector<std::string>{ "(modes unknown: " + modes.error + ")" };
			print_device(info);
		}
		openni2 = listed.value.size();
		if (listed.value.empty()) {
			std::printf("  none\n");
		}
	}

	std::printf("Machine-vision cameras (Aravis: GigE Vision, USB3 Vision):\n");
	const DriverResult<std::vector<DeviceInfo>> listed_cameras = list_aravis_devices(fake);
	if (!listed_cameras.ok()) {
		std::printf("  (none can be listed: %s)\n", listed_cameras.error.c_str());
	}
	std::vector<DeviceInfo> cameras = listed_cameras.value;
	for (DeviceInfo &info : cameras) {
		DriverResult<std::unique_ptr<AravisCamera>> opened = AravisCamera::open(info.id);
		if (!opened.ok()) {
			info.modes = { "(cannot open it to read its modes: " + opened.error + ")" };
		} else {
			const AravisCamera &camera = *opened.value;
			const std::string formats = comma_list(camera.get_available_pixel_formats());
			info.modes = { "sensor " + std::to_string(camera.get_sensor_width()) + "x" + std::to_string(camera.get_sensor_height()) + ", region " +
								   std::to_string(camera.get_width()) + "x" + std::to_string(camera.get_height()) + ", now " + camera.get_pixel_format(),
				"pixel formats: " + (formats.empty() ? std::string("(not listed)") : formats),
				std::string("exposure time: ") + (camera.has_exposure_time() ? "yes" : "no") + ", gain: " + (camera.has_gain() ? "yes" : "no") };
		}
		print_device(info);
	}
	if (cameras.empty() && listed_cameras.ok()) {
		std::printf("  none%s\n", fake ? "" : " (--fake lists Aravis' test camera)");
	}

	std::printf("UVC cameras (V4L2):\n");
	const std::vector<DeviceInfo> nodes = list_v4l2_devices();
	for (const DeviceInfo &info : nodes) {
		print_device(info);
	}
	if (nodes.empty()) {
		std::printf("  none\n");
	}
	std::printf("summary: openni2=%zu aravis=%zu v4l2=%zu\n", openni2, cameras.size(), nodes.size());
	return 0;
}

} // namespace

int main(int p_argc, char **p_argv) {
	return roomprobe::cli::guarded_main("roomprobe_devices", [&] { return run(p_argc, p_argv); });
}
