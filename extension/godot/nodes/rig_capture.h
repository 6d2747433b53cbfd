#pragma once
// RigCapture: where the rig's frames come from: the RGB-D camera and the upward fisheye, two
// unsynchronised streams (paper §3.2, §4.3). Plays a recording (docs/recording-format.md) in
// real time by its timestamps, or one frame per step() call for deterministic tests. Live
// devices (extension/drivers) come later.

#include <recording/recording_reader.h>

#include <rp_godot/godot.h>

#include <math/pose.h>

#include <memory>

namespace roomprobe {

class RigCapture : public godot::Node {
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

	// Processes first: the model nodes read the frames it delivers in the same frame.
	RigCapture() { set_process_priority(-30); }

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

	// For the nodes that consume frames in C++ (DenseSLAM, CoarseRoomModel).
	const RecordingReader *get_reader() const { return reader.get(); }
	const RgbdFrame &get_rgbd_frame() const { return rgbd_frame; }
	const FisheyeFrame &get_fisheye_frame() const { return fisheye_frame; }

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }
	void _ready();
	void _process(double p_delta);

protected:
	static void _bind_methods();

private:
	bool deliver(size_t p_event, bool p_decode);
	void fail(const std::string &p_message);

	godot::String recording_path;
	Pacing pacing = PACING_REAL_TIME;
	bool loop = false;
	bool autoplay = true;

	std::unique_ptr<RecordingReader> reader;
	size_t next_event = 0;
	bool playing = false;
	double clock_s = 0.0; // playback time since the first event, seconds
	int64_t frame_index[2] = { -1, -1 };
	int64_t dropped = 0;
	RgbdFrame rgbd_frame;
	FisheyeFrame fisheye_frame;
	godot::Ref<godot::ImageTexture> rgb_texture, depth_texture, fisheye_texture;
	godot::Ref<godot::Image> rgb_image, depth_image, fisheye_image;
	std::string last_error;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RigCapture::Pacing)
VARIANT_ENUM_CAST(roomprobe::RigCapture::Stream)
