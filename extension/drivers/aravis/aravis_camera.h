#pragma once

// GenICam cameras (GigE Vision, USB3 Vision) through Aravis 0.8: the rig's
// fisheye. Aravis types stay in the plugin (plugin/aravis_plugin.cpp), so this
// header needs no GLib, and RoomProbe's library does not link Aravis.
//
// Not thread-safe: use one AravisCamera from one thread at a time. Aravis'
// device list is process-wide; the functions here serialise their own use of it.

#include "device_types.h"

#include <memory>
#include <string>
#include <vector>

namespace roomprobe::drivers {

// Lists the cameras Aravis finds (backend "aravis"). Takes about a second:
// GigE discovery waits for answers. Aravis' built-in test camera (id "Fake_1")
// is listed only when p_include_fake is true. Fails only when the Aravis plugin
// cannot be loaded (aravis_plugin_problem() says why).
DriverResult<std::vector<DeviceInfo>> list_aravis_devices(bool p_include_fake);

// Empty when the Aravis plugin (libroomprobe_aravis.so) is loaded, else why it is not: not
// installed beside RoomProbe's library, or not loadable. Loads it on the first call.
std::string aravis_plugin_problem();

// A GenICam camera opened through the Aravis plugin, which holds the implementation: Aravis,
// GLib and their libraries load only when a camera is listed or opened (aravis_loader.cpp).
class AravisCamera {
public:
	// Opens a camera by Aravis device id (as listed), or a GigE camera by its IP
	// address. Ids starting with "Fake_" open Aravis' test camera. Takes control
	// of the camera; acquisition starts with the first grab().
	static DriverResult<std::unique_ptr<AravisCamera>> open(const std::string &p_device_id);

	// Waits up to p_timeout_ms for a frame and returns a current one: the newest
	// frame received since the last call, or, when frames piled up in every
	// buffer (the camera then drops newer ones), the next frame to arrive. So a
	// slow caller gets a current image, never a backlog. Acquisition runs
	// continuously into a pool of 4 buffers from the first grab: starting and
	// stopping per frame (arv_camera_acquisition) costs a stream set-up each time
	// and cannot keep up with the camera's frame rate.
	// Only 8-bit formats (Mono8, Bayer*8, RGB8, BGR8) are accepted. A camera that stopped
	// answering (unplugged) gives an error, here and on every later call.
	virtual DriverResult<CameraFrame> grab(int p_timeout_ms) = 0;

	virtual const std::string &get_device_id() const = 0;
	virtual DeviceInfo get_info() const = 0;
	virtual int get_sensor_width() const = 0; // Full sensor, pixels.
	virtual int get_sensor_height() const = 0;
	virtual int get_width() const = 0; // The region grab() returns, pixels.
	virtual int get_height() const = 0;
	virtual std::string get_pixel_format() const = 0; // GenICam name, e.g. "Mono8".
	virtual bool is_streaming() const = 0;
	// True once Aravis' heartbeat found the camera gone; every grab() then fails. Open it again.
	virtual bool is_connection_lost() const = 0;
	// The GenICam names of the pixel formats the camera offers ("Mono8", "BayerRG8", ...).
	virtual std::vector<std::string> get_available_pixel_formats() const = 0;
	// Before the first grab only; fails naming the formats offered.
	virtual DriverStatus set_pixel_format(const std::string &p_format) = 0;
	// ExposureAuto and GainAuto continuous (on) or off, whichever the camera has. Off with
	// neither is not an error (the camera has nothing automatic); on with neither is.
	virtual DriverStatus set_auto_exposure(bool p_on) = 0;

	// Exposure in microseconds and gain in the camera's unit (usually dB). Each
	// setter switches the matching auto mode off and fails, naming the valid
	// range, when the value is out of bounds or the camera lacks the feature.
	virtual bool has_exposure_time() const = 0;
	virtual DriverResult<double> get_exposure_time_us() const = 0;
	virtual DriverStatus set_exposure_time_us(double p_exposure_us) = 0;
	virtual bool has_gain() const = 0;
	virtual DriverResult<double> get_gain() const = 0;
	virtual DriverStatus set_gain(double p_gain) = 0;

	// Stops acquisition (unless the camera is gone) and releases Aravis' objects.
	virtual ~AravisCamera() = default;

	AravisCamera(const AravisCamera &) = delete;
	AravisCamera &operator=(const AravisCamera &) = delete;

protected:
	AravisCamera() = default;
};

} // namespace roomprobe::drivers
