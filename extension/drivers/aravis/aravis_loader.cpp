// Loads the Aravis plugin (aravis_plugin_api.h) the first time an Aravis camera is listed or
// opened. Aravis brings GLib, libxml2 and ICU (about 42 MB in the shipped addon), which an app
// without a GenICam fisheye never needs: the plugin ships apart (docs/addon.md).

#include "aravis/aravis_plugin_api.h"

#include <dlfcn.h>

#include <filesystem>

namespace roomprobe::drivers {

namespace {

struct LoadedPlugin {
	const AravisPluginApi *api = nullptr;
	std::string problem; // Empty when loaded.
};

// The folder of the file this code is in: RoomProbe's library, or a tool or test program that
// links the drivers statically (dladdr names the main program by argv[0]: /proc/self/exe instead).
std::filesystem::path own_folder() {
	Dl_info info{};
	std::error_code error;
	if (dladdr(reinterpret_cast<void *>(&own_folder), &info) && info.dli_fname) {
		const std::filesystem::path file = info.dli_fname;
		if (file.filename().string().find(".so") != std::string::npos) {
			return std::filesystem::absolute(file, error).parent_path();
		}
	}
	return std::filesystem::read_symlink("/proc/self/exe", error).parent_path();
}

// Beside the library (the addon's bin/, build/bin/ for the tools), or in ../bin (the test programs
// in build/tests/).
LoadedPlugin load_plugin() {
	const std::filesystem::path folder = own_folder();
	const std::filesystem::path candidates[] = { folder / ARAVIS_PLUGIN_FILE, folder.parent_path() / "bin" / ARAVIS_PLUGIN_FILE };
	for (const std::filesystem::path &path : candidates) {
		std::error_code error;
		if (!std::filesystem::is_regular_file(path, error)) {
			continue;
		}
		void *handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL); // Never closed: Aravis keeps threads.
		if (!handle) {
			const char *why = dlerror();
			return { nullptr, "the Aravis plugin " + path.string() + " does not load: " + (why ? why : "(no reason given)") };
		}
		using Entry = const AravisPluginApi *(*)();
		const auto entry = reinterpret_cast<Entry>(dlsym(handle, ARAVIS_PLUGIN_ENTRY));
		const AravisPluginApi *api = entry ? entry() : nullptr;
		if (!api) {
			return { nullptr, "the Aravis plugin " + path.string() + " has no " + ARAVIS_PLUGIN_ENTRY + "()" };
		}
		if (api->version != ARAVIS_PLUGIN_VERSION || std::string(api->compiler) != __VERSION__) {
			return { nullptr, "the Aravis plugin " + path.string() + " is from another build (version " + std::to_string(api->version) +
							", " + api->compiler + "; this library: " + std::to_string(ARAVIS_PLUGIN_VERSION) + ", " + __VERSION__ +
							"): install the plugin that came with this RoomProbe" };
		}
		return { api, "" };
	}
	return { nullptr, std::string("the Aravis plugin (") + ARAVIS_PLUGIN_FILE + ") is not installed in " + folder.string() +
							": GigE Vision and USB3 Vision cameras need it (the addon's optional Aravis zip, docs/addon.md)" };
}

const LoadedPlugin &plugin() {
	static const LoadedPlugin loaded = load_plugin(); // Thread-safe, once.
	return loaded;
}

} // namespace

std::string aravis_plugin_problem() {
	return plugin().problem;
}

DriverResult<std::vector<DeviceInfo>> list_aravis_devices(bool p_include_fake) {
	if (!plugin().api) {
		return DriverResult<std::vector<DeviceInfo>>::failure(plugin().problem);
	}
	return DriverResult<std::vector<DeviceInfo>>::success(plugin().api->list_devices(p_include_fake));
}

DriverResult<std::unique_ptr<AravisCamera>> AravisCamera::open(const std::string &p_device_id) {
	if (!plugin().api) {
		return DriverResult<std::unique_ptr<AravisCamera>>::failure("Aravis device '" + p_device_id + "': " + plugin().problem);
	}
	return plugin().api->open(p_device_id);
}

} // namespace roomprobe::drivers
