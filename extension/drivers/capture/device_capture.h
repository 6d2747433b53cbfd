#pragma once
// DeviceCapture: one thread per live device (paper §3.2: the RGB-D camera and the fisheye are two
// unsynchronised streams). The thread opens its CaptureSource, grabs frames, stamps each on the
// rig's one clock (capture_clock.h) and hands it to a sink without touching Godot's main thread
// (RigCapture's sink posts it into the engine's mailbox, engine/live_room.h).
//
// It keeps a state with a reason, and reports every change:
//   Connecting   -> opening the device, or opened and waiting for its first frame
//   Streaming    -> frames arrive
//   Stalled      -> no frame for stall_after_s (a covered lens does not do this; a hung driver
//                   or a recording at its end does)
//   Disconnected -> the device is absent or was lost (unplugged); the thread closes it and opens
//                   it again after a back-off that doubles up to retry_max_s, until it streams
//                   again or stop() is called. Also after reopen_after_s without a frame.
// An absent device is one state change and one reason, not an error per grab.

#include "../device_types.h"
#include "capture_clock.h"

#include <recording/recording_types.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace roomprobe::drivers {

enum class DeviceState {
	Stopped, // start() not called, or stop() returned
	Connecting,
	Streaming,
	Stalled,
	Disconnected,
};

// "stopped", "connecting", "streaming", "stalled", "disconnected".
const char *device_state_name(DeviceState p_state);

// One frame from a live device, stamped by its capture thread. What the device said about it
// (its own clock and frame counter; the fisheye's exposure and gain) is in the frame's capture.
struct CapturedFrame {
	bool is_rgbd = false; // which of the two is filled in
	roomprobe::RgbdFrame rgbd; // timestamp_s and depth_timestamp_s: host_time_s
	roomprobe::FisheyeFrame fisheye; // timestamp_s: host_time_s
	double host_time_s = 0.0; // the rig's clock: monotonic arrival, less the device's latency, seconds
	// Seconds the source spent on the frame after its driver handed it over (conversion, register
	// reads): the arrival stamp is moved back by it, so it biases no timestamp.
	double processing_s = 0.0;
	const roomprobe::CaptureInfo &capture() const { return is_rgbd ? rgbd.capture : fisheye.capture; }
};

// What a CaptureSource's grab gives.
struct GrabOutcome {
	enum Kind {
		Frame, // frame is filled in (its host_time_s is set by DeviceCapture)
		Timeout, // nothing within the time asked: slow, covered, or at the end of a recording
		Lost, // the device is gone or failed; close and open again
	};
	Kind kind = Lost;
	CapturedFrame frame;
	std::string error; // why, naming the device (Timeout and Lost)
};

// A device as a capture thread drives it. Used by one thread at a time; open() may be called
// again after close() (reconnection).
class CaptureSource {
public:
	virtual ~CaptureSource() = default;
	// "Aravis device 'Fake_1'", "OpenNI2 device 'freenect://0'": the prefix of the state reasons.
	virtual std::string name() const = 0;
	virtual DriverStatus open() = 0;
	virtual GrabOutcome grab(int p_timeout_ms) = 0;
	virtual void close() = 0;
};

struct DeviceCaptureOptions {
	double latency_s = 0.0; // subtracted from the arrival time (the rig file's per-device latency)
	double stall_after_s = 1.0; // no frame for this long while streaming: Stalled
	double reopen_after_s = 5.0; // no frame for this long: closed and opened again (Disconnected)
	double retry_first_s = 0.25; // the first back-off after a failed open or a loss
	double retry_max_s = 4.0; // the back-off doubles up to this
	int grab_timeout_ms = 100; // one grab's wait; also how soon stop() is noticed
	ClockNs clock = monotonic_clock_ns;
};

// Where a capture stands; a copy, safe to read from any thread.
struct DeviceStatus {
	DeviceState state = DeviceState::Stopped;
	std::string reason; // why it is in that state (empty while streaming)
	uint64_t frames = 0; // delivered to the sink since start()
	uint64_t reconnections = 0; // times it streamed again after being disconnected or stalled
	uint64_t changes = 0; // state changes since start()
	double last_frame_host_time_s = std::numeric_limits<double>::quiet_NaN();
};

class DeviceCapture {
public:
	using FrameSink = std::function<void(CapturedFrame &&)>;
	// Called on the capture thread after every state change, with the new status.
	using StateSink = std::function<void(const DeviceStatus &)>;

	DeviceCapture(std::unique_ptr<CaptureSource> p_source, const DeviceCaptureOptions &p_options, FrameSink p_on_frame, StateSink p_on_state = nullptr);
	~DeviceCapture(); // stops
	DeviceCapture(const DeviceCapture &) = delete;
	DeviceCapture &operator=(const DeviceCapture &) = delete;

	// Starts the thread (no-op when running). An error when an option is out of range.
	std::string start();
	// Joins the thread within about one grab timeout and closes the device.
	void stop();
	bool is_running() const;
	DeviceStatus status() const;
	std::string name() const { return source_name; }

private:
	void run();
	void set_state(DeviceState p_state, const std::string &p_reason);
	// Waits up to p_seconds or until stop(); false when stopping.
	bool wait(double p_seconds);
	double now_s() const;

	std::unique_ptr<CaptureSource> source;
	std::string source_name;
	DeviceCaptureOptions options;
	FrameSink on_frame;
	StateSink on_state;

	mutable std::mutex mutex;
	std::condition_variable wake;
	bool stopping = false;
	DeviceStatus current;
	bool interrupted = false; // stalled or disconnected since the last frame (counts a reconnection)
	std::thread thread;
	uint64_t last_stamp_ns = 0; // capture thread only: stamps increase strictly
};

} // namespace roomprobe::drivers
