#pragma once

// Plain data shared by the device drivers (Aravis, OpenNI2) and their users
// (RigCapture). No Godot, no vendor headers: copyable values only.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace roomprobe::drivers {

// One device as a backend lists it. Strings the backend does not report are empty.
struct DeviceInfo {
	std::string backend; // "aravis" or "openni2".
	std::string id; // What open() takes: an Aravis device id ("Fake_1", "Basler-2134") or an OpenNI2 URI / .oni path.
	std::string vendor; // Manufacturer as reported by the device, e.g. "Aravis", "PrimeSense".
	std::string model; // Model name, e.g. "Fake", "PS1080".
	std::string serial; // Serial number; empty where listing cannot read it without opening.
	std::vector<std::string> modes; // "depth 640x480 30 Hz 1 mm", "Mono8 1024x1024"...; filled in only by the list_*_modes functions
};

// A value or the reason there is none. Drivers never throw: every failure is a
// message that names the device (or file) and what went wrong. A default-made
// result is a failure, so a result nobody filled in never passes for success.
template <class T>
struct DriverResult {
	T value{}; // Meaningful only when ok().
	std::string error = "no result"; // Empty on success.

	bool ok() const { return error.empty(); }

	static DriverResult success(T p_value) { return DriverResult{ std::move(p_value), std::string() }; }
	static DriverResult failure(std::string p_error) { return DriverResult{ T{}, std::move(p_error) }; }
};

// The outcome of an operation without a value (setters, start/stop).
struct DriverStatus {
	std::string error; // Empty on success.

	bool ok() const { return error.empty(); }
};

// One 8-bit image from a machine-vision camera (the fisheye), as the camera sent it.
// Rows are packed: row y starts at pixels[y * width * channels], no padding.
struct CameraFrame {
	int width = 0; // Pixels.
	int height = 0; // Pixels.
	int channels = 1; // 1 (Mono8, a Bayer mosaic) or 3 (RGB8, BGR8).
	std::string pixel_format; // GenICam name: "Mono8", "RGB8", or a Bayer mosaic such as "BayerRG8" (not demosaiced: capture/pixel_formats.h does that).
	std::vector<uint8_t> pixels; // width * height * channels bytes.
	uint64_t timestamp_ns = 0; // Exposure time stamp from the camera's clock, nanoseconds; the host time below when the camera gives none.
	uint64_t host_timestamp_ns = 0; // Host monotonic clock (capture/capture_clock.h) when grab() took the frame, nanoseconds.
	uint64_t frame_id = 0; // The camera's frame counter (wraps; gaps mean dropped frames).
};

// One depth image from an OpenNI2 device or recording.
struct DepthFrame {
	int width = 0; // Pixels.
	int height = 0; // Pixels.
	std::vector<uint16_t> depth_mm; // width * height distances along the optical axis, millimetres; 0 = no measurement.
	bool registered_to_color = false; // True when the device mapped depth into the colour camera's pixels.
	uint64_t timestamp_ns = 0; // Device clock (OpenNI2 gives microseconds), nanoseconds; a recording's own time line.
	uint64_t host_timestamp_ns = 0; // Host monotonic clock (capture/capture_clock.h) when the frame was read, nanoseconds.
	int frame_index = 0; // The stream's frame counter.
};

// One colour image from an OpenNI2 device or recording.
struct ColorFrame {
	int width = 0; // Pixels.
	int height = 0; // Pixels.
	std::vector<uint8_t> rgb; // width * height * 3 bytes, R, G, B per pixel, rows packed.
	uint64_t timestamp_ns = 0; // Device clock, nanoseconds (see DepthFrame).
	uint64_t host_timestamp_ns = 0; // Host monotonic clock (capture/capture_clock.h) when the frame was read, nanoseconds.
	int frame_index = 0; // The stream's frame counter.
};

// A depth and a colour frame grabbed together, as the device gives them (each with its own time
// stamps, depth in millimetres): capture/capture_sources.cpp makes the core's RgbdFrame of it.
struct RgbdGrab {
	DepthFrame depth;
	ColorFrame color;
};

// "a, b, c", for messages and listings.
inline std::string comma_list(const std::vector<std::string> &p_items) {
	std::string text;
	for (const std::string &item : p_items) {
		text += (text.empty() ? "" : ", ") + item;
	}
	return text;
}

// "3 devices listed: a, b, c" (or "no devices listed"), for errors about a device not found.
inline std::string describe_listed(const std::vector<DeviceInfo> &p_devices) {
	if (p_devices.empty()) {
		return "no devices listed";
	}
	std::string listed = std::to_string(p_devices.size()) + (p_devices.size() == 1 ? " device" : " devices") + " listed: ";
	for (size_t i = 0; i < p_devices.size(); i++) {
		listed += (i ? ", " : "") + p_devices[i].id;
	}
	return listed;
}

} // namespace roomprobe::drivers
