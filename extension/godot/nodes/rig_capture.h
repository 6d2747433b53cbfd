#pragma once
// RigCapture: where the rig's frames come from: the RGB-D camera and the upward fisheye, two
// unsynchronised streams (paper §3.2, §4.3). Plays a recording (docs/recording-format.md) and
// feeds every frame into the scene's live engine (engine/live_room.h), which it owns:
// Both pacings go through source/paced_player.h, as every player of a recording does:
//   Real Time: its capture thread reads and decodes the frames due by the scene's clock (the
//     process delta summed, so Movie Maker's fixed steps play it at recorded speed) and posts
//     them to the engine's workers; the main thread only shows the newest frames as textures,
//     and only those asked for.
//   Step: one frame per step() call, read here and processed by the engine before step() returns
//     (its step mode): deterministic, for tests.
// Or it streams the live rig (source Live): drivers/capture/live_rig.h runs a capture thread per
// device, whose frames go straight into the engine; the node only shows device states (signal,
// warnings), the newest frames, and starts and stops recordings.

#include "../convert/camera_feed_convert.h"
#include "live_room_link.h"

#include <capture/live_rig.h>
#include <recording/recording_reader.h>
#include <source/paced_player.h>

#include <rp_godot/godot.h>

#include <math/pose.h>

#include <atomic>
#include <memory>
#include <mutex>

namespace roomprobe {

class RigCapture : public godot::Node, public LiveRoomHost {
	GDCLASS(RigCapture, godot::Node)

public:
	enum Pacing {
		PACING_REAL_TIME, // Frames follow their timestamps.
		PACING_STEP, // One frame per step() call: deterministic, for tests.
	};
	enum Stream {
		STREAM_RGBD,
		STREAM_FISHEYE,
	};
	enum Source {
		SOURCE_RECORDING, // recording_path
		SOURCE_LIVE, // the devices, with rig_file
	};
	enum FisheyeBackend {
		FISHEYE_BACKEND_ARAVIS, // GigE Vision / USB3 Vision
		FISHEYE_BACKEND_UVC, // a V4L2 webcam (OpenCV's VideoCapture)
		FISHEYE_BACKEND_CAMERA_FEED, // a Godot CameraServer feed (rig_capture_feed.cpp)
	};
	enum ComputeBackendMode { // ComputeBackend (gpu/compute_device.h), in its order
		COMPUTE_BACKEND_CPU,
		COMPUTE_BACKEND_VULKAN,
		COMPUTE_BACKEND_AUTO,
	};
	enum DeviceState { // drivers::DeviceState, in its order
		DEVICE_STATE_STOPPED,
		DEVICE_STATE_CONNECTING,
		DEVICE_STATE_STREAMING,
		DEVICE_STATE_STALLED,
		DEVICE_STATE_DISCONNECTED,
	};

	// Processes first: the model nodes read the results of the frames it delivers in the same frame.
	RigCapture();
	~RigCapture();

	void set_recording_path(const godot::String &p_path);
	godot::String get_recording_path() const;
	void set_pacing(int64_t p_pacing);
	Pacing get_pacing() const;
	void set_loop(bool p_loop);
	bool get_loop() const;
	void set_autoplay(bool p_autoplay);
	bool get_autoplay() const;
	void set_source(int64_t p_source);
	Source get_source() const;
	void set_rig_file(const godot::String &p_path);
	godot::String get_rig_file() const;
	void set_room_file(const godot::String &p_path);
	godot::String get_room_file() const;
	void set_rgbd_device(const godot::String &p_uri);
	godot::String get_rgbd_device() const;
	void set_fisheye_device(const godot::String &p_id);
	godot::String get_fisheye_device() const;
	void set_compute_backend(int64_t p_backend);
	ComputeBackendMode get_compute_backend() const;
	void set_fisheye_backend(int64_t p_backend);
	FisheyeBackend get_fisheye_backend() const;
	void set_fisheye_pixel_format(const godot::String &p_format);
	godot::String get_fisheye_pixel_format() const;
	void set_auto_exposure(bool p_on);
	bool get_auto_exposure() const;
	void set_exposure_us(double p_exposure_us);
	double get_exposure_us() const;
	void set_gain(double p_gain);
	double get_gain() const;

	// Live source: each device's state and why, and recording the live streams.
	DeviceState get_device_state(Stream p_stream) const;
	godot::String get_device_state_reason(Stream p_stream) const;
	godot::Dictionary get_device_status(Stream p_stream) const;
	bool start_recording(const godot::String &p_folder);
	bool stop_recording();
	bool is_recording() const;
	godot::Dictionary get_recording_status() const;

	bool open();
	void close();
	bool is_open() const;
	void play();
	void stop();
	bool is_playing() const;
	bool step();
	void rewind();

	int64_t get_frame_count(Stream p_stream) const;
	int64_t get_event_count() const;
	int64_t get_event_position() const;
	double get_time() const;
	int64_t get_frame_index(Stream p_stream) const;
	double get_frame_timestamp(Stream p_stream) const;
	int64_t get_dropped_frame_count() const;
	godot::Ref<godot::ImageTexture> get_rgb_texture() const;
	godot::Ref<godot::ImageTexture> get_depth_texture() const;
	godot::Ref<godot::ImageTexture> get_fisheye_texture() const;
	// The same frames as images in memory, for scripts that read pixels.
	godot::Ref<godot::Image> get_rgb_image() const;
	godot::Ref<godot::Image> get_depth_image() const;
	godot::Ref<godot::Image> get_fisheye_image() const;
	// The recording's room (room.yaml): floorplan corners (x, z) in metres, ceiling height in
	// metres, probe positions in world metres. Empty / 0 without a room.
	godot::PackedVector2Array get_room_floorplan() const;
	double get_room_ceiling_height() const;
	godot::PackedVector3Array get_probe_positions() const;
	bool has_ground_truth() const;
	// The ground-truth pose of the RGB camera at the current RGB-D frame, as a Godot camera
	// transform (looking down -Z, Y up); identity without ground truth or frame.
	godot::Transform3D get_ground_truth_camera_transform() const;
	// The RGB camera's vertical field of view, degrees (for Camera3D.fov); 0 without a recording.
	double get_rgb_camera_fov() const;
	godot::PackedStringArray get_issues() const;
	godot::String get_last_error() const;

	// The engine every other node of the rig configures and reads.
	std::shared_ptr<LiveRoom> get_live_room() const override { return engine; }
	// Microseconds RoomProbe's nodes have spent on the main thread (MainThreadTimer), for the demo.
	static int64_t get_main_thread_usec();
	// The same split: wall_usec, cpu_usec, and each node class's wall-clock microseconds.
	static godot::Dictionary get_main_thread_times();

	// fisheye_backend Camera Feed: the feed's frame_changed signal, on whichever thread it comes.
	void _camera_feed_frame();

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }
	void _ready();
	void _process(double p_delta);

protected:
	static void _bind_methods();
	void _notification(int p_what);

private:
	static void bind_properties(); // _bind_methods' second half: properties, constants, signals
	// A decoded frame to show and signal, handed from whoever read it to the main thread.
	struct Shown {
		RgbdFrame rgbd;
		FisheyeFrame fisheye;
		int64_t index[2] = { -1, -1 };
		uint64_t version[2] = { 0, 0 };
	};
	// Any capture thread: the frame goes to the engine and becomes the newest for the main thread.
	// p_index: its index in its stream; -1 counts the live device's frames instead.
	void deliver(bool p_is_rgbd, RgbdFrame &&p_rgbd, FisheyeFrame &&p_fisheye, int64_t p_index);
	void deliver_recorded(SourceFrame &&p_frame); // the player's sink, and step()'s
	void show_frames(bool p_signal);
	// The textures of the newest RGB-D and / or fisheye frame (made on first use).
	void update_textures(bool p_rgbd, bool p_fisheye) const;
	void configure_engine();
	void fail(const std::string &p_message);
	bool open_live();
	bool path_on_disk(const char *p_property, const godot::String &p_value, std::string *r_path);
	void start_live();
	// Main thread: emits device_state_changed for the changes the capture threads queued.
	void report_device_states();
	const RoomInfo *preview_room() const; // before opening (the editor): room.yaml of recording_path
	mutable godot::String previewed_path; // preview_room()'s cache
	mutable RoomInfo preview;
	mutable bool has_preview_room = false;
	const RoomInfo *room_info() const; // the recording's room, or room_file's (live); null without
	const Rig *rig_info() const; // the recording's rig, or rig_file's (live); null when not open
	const RecordingReader *recording_reader() const; // null when no recording is open
	void reopen_if_live();
	// fisheye_backend Camera Feed, main thread (rig_capture_feed.cpp): finds the feed, connects to
	// it, and pushes its newest frame to the fisheye's capture thread.
	std::shared_ptr<drivers::PushedFrames> start_camera_feed(); // start_live: a fresh PushedFrames, the feed looked for
	void poll_camera_feed();
	bool follow_camera_feed(); // false while the feed is not listed (the reason is pushed as absent)
	void release_camera_feed();

	godot::String recording_path;
	Source source = SOURCE_RECORDING;
	godot::String rig_file, room_file, rgbd_device, fisheye_device, fisheye_pixel_format;
	FisheyeBackend fisheye_backend = FISHEYE_BACKEND_ARAVIS;
	ComputeBackendMode compute_backend = COMPUTE_BACKEND_CPU;
	bool auto_exposure = true;
	double exposure_us = 10000.0;
	double gain = 0.0;
	Pacing pacing = PACING_REAL_TIME;
	bool loop = false;
	bool autoplay = true;
	// What get_warnings() found when it last checked an unopened recording_path / rig_file (so the
	// editor does not read them again for every warning refresh).
	mutable std::string checked_recording, recording_problem, checked_rig, rig_problem;

	std::shared_ptr<LiveRoom> engine;
	bool playing = false;
	// Live source: opened (rig_file read) while live_rig holds a value.
	std::unique_ptr<drivers::LiveRig> live;
	bool live_open = false;
	Rig live_rig;
	bool has_live_room = false;
	RoomInfo live_room;
	struct StateChange {
		Stream stream = STREAM_RGBD;
		drivers::DeviceStatus status;
	};

	// Shared with the capture threads (the player's, the live devices'), under mutex.
	mutable std::mutex mutex;
	std::vector<std::string> frame_warnings; // unreadable frames, printed by the main thread
	std::vector<StateChange> state_changes; // device state changes, signalled by the main thread
	int64_t live_frames[2] = { 0, 0 }; // frames the live devices delivered since play()
	Shown latest;
	// The open recording (is_open()): its position, clock, drop count and capture thread, under
	// its own lock. Its sink reaches the members above, so it is stopped first (~RigCapture).
	PacedPlayer player;

	// Main thread only.
	uint64_t shown_version[2] = { 0, 0 };
	int64_t frame_index[2] = { -1, -1 };
	RgbdFrame rgbd_frame; // the newest shown
	FisheyeFrame fisheye_frame;
	mutable bool textures_wanted = false;
	mutable godot::Ref<godot::ImageTexture> rgb_texture, depth_texture, fisheye_texture;
	mutable godot::Ref<godot::Image> rgb_image, depth_image, fisheye_image;
	mutable bool images_stale = true;
	std::string last_error;
	drivers::DeviceStatus device_status[2]; // the last state signalled, per stream
	// fisheye_backend Camera Feed: the feed followed, its reader, and the frames its signal counted.
	std::shared_ptr<drivers::PushedFrames> feed_frames; // made by start_live, read by the fisheye's capture thread
	godot::Ref<godot::CameraFeed> feed;
	bool feed_activated = false; // this node turned the feed on, and turns it off
	CameraFeedReader feed_reader;
	std::atomic<uint64_t> feed_signals{ 0 }; // written by the feed's thread
	std::atomic<uint64_t> feed_arrival_ns{ 0 };
	uint64_t feed_taken = 0;
	std::string feed_absent; // the reason last pushed as absent
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RigCapture::Pacing)
VARIANT_ENUM_CAST(roomprobe::RigCapture::Stream)
VARIANT_ENUM_CAST(roomprobe::RigCapture::Source)
VARIANT_ENUM_CAST(roomprobe::RigCapture::FisheyeBackend)
VARIANT_ENUM_CAST(roomprobe::RigCapture::ComputeBackendMode)
VARIANT_ENUM_CAST(roomprobe::RigCapture::DeviceState)
