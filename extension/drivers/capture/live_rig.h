#pragma once
// LiveRig: the rig's live devices as one (paper §3.2): a capture thread for the RGB-D camera and
// one for the fisheye (device_capture.h), made from the rig file and the device settings, both
// stamping on the host's monotonic clock less the rig file's per-device latency. Every frame
// goes to one sink (RigCapture's posts it into the engine; the record tool has none) and, while
// a recording runs, into it (recording_queue.h), from the capture thread, never Godot's main one.

#include "capture_sources.h"
#include "device_capture.h"
#include "pushed_camera.h"

#include <recording/recording_queue.h>
#include <rig/rig.h>

#include <functional>
#include <memory>
#include <mutex>
#include <string>

namespace roomprobe::drivers {

enum class FisheyeBackend {
	Aravis, // GigE Vision, USB3 Vision
	Uvc, // a V4L2 webcam through OpenCV's VideoCapture
	Pushed, // frames the host pushes (LiveRigSettings::pushed_fisheye): Godot's camera feeds
};

struct LiveRigSettings {
	bool use_rgbd = true;
	bool use_fisheye = true; // off by itself when the rig has no fisheye
	RgbdSourceSettings rgbd; // its size comes from the rig
	FisheyeSourceSettings fisheye; // its size comes from the rig
	FisheyeBackend fisheye_backend = FisheyeBackend::Aravis;
	std::shared_ptr<PushedFrames> pushed_fisheye; // FisheyeBackend::Pushed: where the host pushes them
	DeviceCaptureOptions capture; // latency_s comes from the rig, per device
};

// The rig as live capture stamps its frames: the file's, with fisheye_time_offset_s 0 (both
// streams on the host's one clock). What a LiveRig records, and what the engine must be given.
Rig live_capture_rig(const Rig &p_rig);

class LiveRig {
public:
	using FrameSink = DeviceCapture::FrameSink;
	// Called on a capture thread after every state change of that stream's device.
	using StateSink = std::function<void(RecordingStream, const DeviceStatus &)>;

	LiveRig() = default;
	~LiveRig(); // stop()
	LiveRig(const LiveRig &) = delete;
	LiveRig &operator=(const LiveRig &) = delete;

	// Starts the capture threads. An error (naming the setting) when nothing would be captured or
	// an option is out of range; an absent device is not an error but a state (Connecting, then
	// Disconnected with its reason, retried with back-off).
	std::string start(const Rig &p_rig, const LiveRigSettings &p_settings, FrameSink p_on_frame, StateSink p_on_state = nullptr);
	// Joins the capture threads (within about one grab timeout each) and closes the devices. A
	// running recording goes on taking nothing until stop_recording().
	void stop();
	bool is_running() const;
	bool uses(RecordingStream p_stream) const;
	// Stopped for a stream that is not captured.
	DeviceStatus status(RecordingStream p_stream) const;
	std::string device_name(RecordingStream p_stream) const;
	// The rig the frames are on: the file's, with fisheye_time_offset_s 0 (one clock for both).
	const Rig &get_rig() const { return rig; }

	// Records the live streams into p_folder (new or empty; never overwritten), with p_room
	// written as its room.yaml when given, and p_options' queue and frame format. Needs start() first.
	RecordingStatus start_recording(const std::string &p_folder, const RoomInfo *p_room = nullptr,
			const RecordingQueueOptions &p_options = RecordingQueueOptions());
	// Writes what is queued and closes; the first error of the whole recording.
	RecordingStatus stop_recording();
	bool is_recording() const;
	RecordingQueueStatus recording_status() const; // of the last recording, after it stopped

private:
	void deliver(CapturedFrame &&p_frame);

	Rig rig;
	FrameSink on_frame;
	std::unique_ptr<DeviceCapture> captures[2]; // by RecordingStream
	mutable std::mutex recording_mutex; // guards recording (the capture threads push into it)
	std::shared_ptr<RecordingQueue> recording;
	RecordingQueueStatus last_recording;
};

} // namespace roomprobe::drivers
