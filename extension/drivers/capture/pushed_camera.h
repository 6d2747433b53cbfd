#pragma once
// A camera whose frames its host pushes, for cameras that only the host can reach: Godot's
// CameraServer feeds (Android's cameras, a headset's passthrough, V4L2 webcams through Godot),
// which RigCapture reads on Godot's main thread. The host stamps each frame on the monotonic
// clock (capture_clock.h) when it arrives and pushes it; a DeviceCapture thread then takes it as
// it takes any device's frame, so states, stalls, latency and recording work alike.
// Only the newest frame waits: a host that pushes faster than the engine takes loses frames,
// never delay.

#include "device_capture.h"

#include <opencv2/core.hpp>

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace roomprobe::drivers {

class PushedFrames {
public:
	// p_name names the camera in states and errors: "Godot camera feed 'Integrated Camera'".
	explicit PushedFrames(std::string p_name) :
			camera_name(std::move(p_name)) {}

	std::string name() const;
	void set_name(std::string p_name);
	// Any thread. p_image: 8-bit RGB (CV_8UC3) or grey (CV_8UC1), kept as given (not copied).
	// p_arrival_ns: monotonic_clock_ns() when the frame reached the host; p_frame_id counts frames.
	void push(cv::Mat p_image, uint64_t p_arrival_ns, int64_t p_frame_id);
	// Any thread: the camera is absent (p_reason says why, without the name), or, with an empty
	// reason, present again. While absent, open() fails with the reason.
	void set_absent(std::string p_reason);
	uint64_t pushed_count() const;

	// The capture thread's side (its CaptureSource).
	std::string absent_reason() const;
	// Waits up to p_timeout_ms for a frame; false without one. Takes it out.
	bool take(int p_timeout_ms, cv::Mat *r_image, uint64_t *r_arrival_ns, int64_t *r_frame_id);
	void drop_waiting(); // forgets a frame that waits (a reopened camera starts afresh)

private:
	mutable std::mutex mutex;
	std::condition_variable arrived;
	std::string camera_name;
	std::string absent; // empty: present (or not looked for yet)
	cv::Mat image;
	uint64_t arrival_ns = 0;
	int64_t frame_id = -1;
	bool waiting = false;
	uint64_t pushed = 0;
};

// A fisheye CaptureSource over p_frames, checking each frame against the rig's fisheye size
// (p_width x p_height; 0: any).
std::unique_ptr<CaptureSource> make_pushed_fisheye_source(std::shared_ptr<PushedFrames> p_frames, int p_width, int p_height);

} // namespace roomprobe::drivers
