#pragma once

// The entry point of the Aravis plugin, libroomprobe_aravis.so (plugin/aravis_plugin.cpp), which
// aravis_loader.cpp finds with dlopen. C++ types cross between the two, so the plugin must come
// from the same build as the library that loads it: the version and the compiler are checked.

#include "aravis/aravis_camera.h"

namespace roomprobe::drivers {

constexpr int ARAVIS_PLUGIN_VERSION = 1; // Raise with any change to AravisPluginApi or AravisCamera.
constexpr const char *ARAVIS_PLUGIN_FILE = "libroomprobe_aravis.so";
constexpr const char *ARAVIS_PLUGIN_ENTRY = "roomprobe_aravis_plugin"; // extern "C", returns const AravisPluginApi *.

struct AravisPluginApi {
	int version; // ARAVIS_PLUGIN_VERSION of the plugin's build.
	const char *compiler; // __VERSION__ of the plugin's build.
	std::vector<DeviceInfo> (*list_devices)(bool p_include_fake);
	DriverResult<std::unique_ptr<AravisCamera>> (*open)(const std::string &p_device_id);
};

} // namespace roomprobe::drivers
