#pragma once
// RigCapture: where the rig's frames come from: the RGB-D camera and the upward fisheye, two
// unsynchronised streams (paper §3.2, §4.3). Plays a recording (docs/recording-format.md) and
// feeds every frame into the scene's live engine (engine/live_room.h), which it owns:
//   Real Time: a capture thread reads and decodes the frames due by the scene's clock (the
//     process delta summed, so Movie Maker's fixed steps play it at recorded speed) and posts
//     them to the engine's workers; the main thread only shows the newest frames as textures,
//     and only those asked for.
//   Step: one frame per step() call, read here and processed by the engine before step() returns
//     (its step mode): deterministic, for tests.
// Live devices (extension/drivers) come later.

#include "live_room_link.h"

#include <recording/recording_reader.h>

#include <rp_godot/godot.h>

#include <math/pose.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

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

	// Processes first: the model nodes read the results of the frames it delivers in the same frame.
	RigCapture();
	~RigCapture();

	void set_recording_path(const godot::String &p_path);
	godot::String get_recording_path() const;
	void set_pacing(Pacing p_pacing);
	Pacing get_pacing() const;
	void set_loop(bool p_loop);
	bool get_loop() const;
	void set_autoplay(bool p_autoplay);
	bool get_autoplay() const;

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

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }
	void _ready();
	void _process(double p_delta);

protected:
	static void _bind_methods();
	void _notification(int p_what);

private:
	// A decoded frame to show and signal, handed from whoever read it to the main thread.
	struct Shown {
		RgbdFrame rgbd;
		FisheyeFrame fisheye;
		int64_t index[2] = { -1, -1 };
		uint64_t version[2] = { 0, 0 };
	};
	bool read_event(size_t p_event);
	void capture_loop();
	void start_capture();
	void stop_capture();
	void show_frames(bool p_signal);
	// The textures of the newest RGB-D and / or fisheye frame (made on first use).
	void update_textures(bool p_rgbd, bool p_fisheye) const;
	void configure_engine();
	void fail(const std::string &p_message);

	godot::String recording_path;
	Pacing pacing = PACING_REAL_TIME;
	bool loop = false;
	bool autoplay = true;

	std::shared_ptr<LiveRoom> engine;
	std::shared_ptr<const RecordingReader> reader; // read_* is const: the capture thread reads frames
	bool playing = false;

	// Shared with the capture thread, under mutex.
	mutable std::mutex mutex;
	std::condition_variable clock_advanced;
	std::thread capture_thread;
	bool capture_stop = false;
	size_t next_event = 0;
	double clock_s = 0.0; // playback time since the first event, seconds (the scene's clock)
	int64_t dropped = 0;
	bool reached_end = false; // the capture thread played the last event (the main thread signals it)
	std::vector<std::string> frame_warnings; // unreadable frames, printed by the main thread
	Shown latest;

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
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RigCapture::Pacing)
VARIANT_ENUM_CAST(roomprobe::RigCapture::Stream)
