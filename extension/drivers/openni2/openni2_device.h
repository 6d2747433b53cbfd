#pragma once

// Depth cameras (Kinect, Xtion: OpenNI2's PS1080 driver) and .oni recordings
// (OniFile driver) through OpenNI 2.2. OpenNI types stay in the .cpp.
//
// OpenNI is initialised on first use and shut down when the last user (an
// open device, an OpenNI2Session, a listing in progress) is gone. Nothing needs
// setting up:
// OpenNI reads /etc/openni2/OpenNI.ini (Debian) and loads its drivers from
// <directory of libOpenNI2.so>/OpenNI2/Drivers.
// Not thread-safe per device: use one OpenNI2Device from one thread at a time.

#include "device_types.h"

#include <memory>
#include <string>
#include <vector>

namespace roomprobe::drivers {

// Lists the depth cameras plugged in (backend "openni2"; serial is left empty,
// it needs the device opened). No device is an empty list, not an error; an
// error means OpenNI itself could not start.
DriverResult<std::vector<DeviceInfo>> list_openni2_devices();

// The video modes a device (or recording) offers, one text a mode: "depth 640x480 30 Hz 1 mm",
// "colour 1280x1024 15 Hz RGB888". Opens the device for a moment.
DriverResult<std::vector<std::string>> list_openni2_modes(const std::string &p_uri);

// Keeps OpenNI initialised while held, so listing and opening reuse it.
// OpenNI 2.2's drivers leak about 110 KB on every initialise/shutdown cycle, so
// a caller that lists again and again (a device picker) should hold one.
class OpenNI2Session {
public:
	OpenNI2Session() = default; // Holds nothing.
	static DriverResult<OpenNI2Session> start();
	bool is_active() const { return runtime != nullptr; }

private:
	std::shared_ptr<void> runtime;
};

class OpenNI2Device {
public:
	// Opens a device by URI (as listed) or plays back a recording: a path to an
	// existing file, or any path ending in ".oni". A live device streams depth in
	// millimetres and RGB colour at 640x480 when it offers that, with depth
	// registered to colour and depth/colour frame sync where supported. A
	// recording plays once (no repeat) at its recorded pace, every frame in order:
	// OpenNI's player runs in its manual mode and a grab holds each frame until
	// its time, so a slow reader falls behind instead of skipping frames.
	static DriverResult<std::unique_ptr<OpenNI2Device>> open(const std::string &p_uri);

	// Each waits up to p_timeout_ms (>= 0) for the next frame of its stream.
	// Errors name the device: no such stream, timeout (end of a recording, an
	// unplugged camera), an unsupported pixel format.
	DriverResult<DepthFrame> grab_depth(int p_timeout_ms);
	DriverResult<ColorFrame> grab_color(int p_timeout_ms);
	// The next depth frame, then the next colour frame, within p_timeout_ms in all.
	DriverResult<RgbdGrab> grab(int p_timeout_ms);

	DeviceInfo get_info() const; // Serial filled in where the device reports one.
	bool is_file() const; // Playing back a recording.
	bool has_depth() const;
	bool has_color() const;
	bool is_depth_registered() const; // Depth pixels are mapped onto colour pixels.
	// True once OpenNI reported the device unplugged; every grab then fails. Open it again.
	bool is_disconnected() const;

	// Stops and destroys the streams, closes the device, releases OpenNI.
	~OpenNI2Device();

	OpenNI2Device(const OpenNI2Device &) = delete;
	OpenNI2Device &operator=(const OpenNI2Device &) = delete;

private:
	friend DriverResult<std::vector<std::string>> list_openni2_modes(const std::string &p_uri);
	struct State; // OpenNI objects, defined in the .cpp.

	explicit OpenNI2Device(std::unique_ptr<State> p_state);

	std::unique_ptr<State> state;
};

} // namespace roomprobe::drivers
