#include "rig_capture.h"

#include "../convert/image_convert.h"
#include "../convert/pose_convert.h"

#include <cmath>

using namespace godot;

namespace roomprobe {

void RigCapture::set_recording_path(const String &p_path) {
	recording_path = p_path;
	last_error.clear(); // the error was about the previous recording
	close();
	update_configuration_warnings();
}

String RigCapture::get_recording_path() const { return recording_path; }
void RigCapture::set_pacing(Pacing p_pacing) { pacing = p_pacing; }
RigCapture::Pacing RigCapture::get_pacing() const { return pacing; }
void RigCapture::set_loop(bool p_loop) { loop = p_loop; }
bool RigCapture::get_loop() const { return loop; }
void RigCapture::set_autoplay(bool p_autoplay) { autoplay = p_autoplay; }
bool RigCapture::get_autoplay() const { return autoplay; }

void RigCapture::fail(const std::string &p_message) {
	last_error = p_message;
	ERR_PRINT(String(("RigCapture: " + p_message).c_str()));
	update_configuration_warnings();
}

bool RigCapture::open() {
	close();
	if (recording_path.is_empty()) {
		fail("recording_path is empty");
		return false;
	}
	// res:// and user:// paths work as well as absolute ones.
	const std::string folder = ProjectSettings::get_singleton()->globalize_path(recording_path).utf8_string();
	auto opened = std::make_unique<RecordingReader>();
	const RecordingStatus status = opened->open(folder);
	if (!status.ok) {
		fail(status.error);
		return false;
	}
	reader = std::move(opened);
	last_error.clear();
	update_configuration_warnings();
	return true;
}

void RigCapture::close() {
	reader.reset();
	playing = false;
	rewind();
}

bool RigCapture::is_open() const { return reader != nullptr; }

void RigCapture::play() {
	if (!reader && !open()) {
		return;
	}
	playing = true;
	set_process(pacing == PACING_REAL_TIME);
}

void RigCapture::stop() {
	playing = false;
	set_process(false);
}

bool RigCapture::is_playing() const { return playing; }

void RigCapture::rewind() {
	next_event = 0;
	clock_s = 0.0;
	frame_index[0] = frame_index[1] = -1;
	dropped = 0;
}

// Decodes the frame of event p_event (unless it was overtaken, p_decode false) and signals it.
bool RigCapture::deliver(size_t p_event, bool p_decode) {
	const PlaybackEvent &event = reader->get_events()[p_event];
	const int stream = event.stream == RecordingStream::Rgbd ? STREAM_RGBD : STREAM_FISHEYE;
	if (!p_decode) {
		dropped++;
		return true;
	}
	if (stream == STREAM_RGBD) {
		RgbdFrameResult result = reader->read_rgbd(event.index);
		if (!result.ok) {
			// One bad frame is skipped; playback goes on.
			WARN_PRINT(String(("RigCapture: " + result.error).c_str()));
			return false;
		}
		rgbd_frame = std::move(result.frame);
		rgb_image = image_from_mat(rgbd_frame.rgb);
		depth_image = image_from_mat(rgbd_frame.depth_m);
		show_in_texture(rgb_image, rgb_texture);
		show_in_texture(depth_image, depth_texture);
	} else {
		FisheyeFrameResult result = reader->read_fisheye(event.index);
		if (!result.ok) {
			WARN_PRINT(String(("RigCapture: " + result.error).c_str()));
			return false;
		}
		fisheye_frame = std::move(result.frame);
		fisheye_image = image_from_mat(fisheye_frame.image);
		show_in_texture(fisheye_image, fisheye_texture);
	}
	frame_index[stream] = int64_t(event.index);
	const double timestamp = stream == STREAM_RGBD ? rgbd_frame.timestamp_s : fisheye_frame.timestamp_s;
	emit_signal("frame_captured", stream, int64_t(event.index), timestamp);
	return true;
}

bool RigCapture::step() {
	if (!reader && !open()) {
		return false;
	}
	const auto &events = reader->get_events();
	if (next_event >= events.size()) {
		if (!loop || events.empty()) {
			return false;
		}
		rewind();
	}
	const size_t event = next_event++;
	clock_s = events[event].time_s - events.front().time_s;
	deliver(event, true);
	if (next_event >= events.size()) {
		emit_signal("finished");
		if (!loop) {
			stop();
		}
	}
	return true;
}

void RigCapture::_ready() {
	// Frames play in the running game; the editor only shows the node's configuration.
	if (autoplay && !Engine::get_singleton()->is_editor_hint() && !recording_path.is_empty()) {
		play();
	}
}

void RigCapture::_process(double p_delta) {
	if (!playing || !reader || pacing != PACING_REAL_TIME) {
		return;
	}
	const auto &events = reader->get_events();
	clock_s += p_delta;
	// Of the frames now due, only the newest of each stream is decoded: a slow frame loop drops
	// frames instead of falling ever further behind.
	size_t due_end = next_event;
	while (due_end < events.size() && events[due_end].time_s - events.front().time_s <= clock_s) {
		due_end++;
	}
	for (size_t e = next_event; e < due_end; e++) {
		bool newest = true;
		for (size_t later = e + 1; later < due_end; later++) {
			newest = newest && events[later].stream != events[e].stream;
		}
		deliver(e, newest);
	}
	next_event = due_end;
	if (next_event >= events.size()) {
		emit_signal("finished");
		if (loop) {
			rewind();
		} else {
			stop();
		}
	}
}

int64_t RigCapture::get_frame_count(Stream p_stream) const {
	if (!reader) {
		return 0;
	}
	return int64_t(p_stream == STREAM_RGBD ? reader->rgbd_count() : reader->fisheye_count());
}

int64_t RigCapture::get_event_count() const { return reader ? int64_t(reader->get_events().size()) : 0; }
int64_t RigCapture::get_event_position() const { return int64_t(next_event); }
double RigCapture::get_time() const { return clock_s; }
int64_t RigCapture::get_frame_index(Stream p_stream) const { return frame_index[p_stream == STREAM_RGBD ? 0 : 1]; }

double RigCapture::get_frame_timestamp(Stream p_stream) const {
	if (get_frame_index(p_stream) < 0) {
		return -1.0;
	}
	return p_stream == STREAM_RGBD ? rgbd_frame.timestamp_s : fisheye_frame.timestamp_s;
}

int64_t RigCapture::get_dropped_frame_count() const { return dropped; }
Ref<ImageTexture> RigCapture::get_rgb_texture() const { return rgb_texture; }
Ref<ImageTexture> RigCapture::get_depth_texture() const { return depth_texture; }
Ref<ImageTexture> RigCapture::get_fisheye_texture() const { return fisheye_texture; }
Ref<Image> RigCapture::get_rgb_image() const { return rgb_image; }
Ref<Image> RigCapture::get_depth_image() const { return depth_image; }
Ref<Image> RigCapture::get_fisheye_image() const { return fisheye_image; }

PackedStringArray RigCapture::get_issues() const {
	PackedStringArray out;
	if (reader) {
		for (const RecordingIssue &issue : reader->get_issues()) {
			out.push_back(String(roomprobe::to_string(issue).c_str()));
		}
	}
	return out;
}

String RigCapture::get_last_error() const { return String(last_error.c_str()); }

PackedVector2Array RigCapture::get_room_floorplan() const {
	PackedVector2Array points;
	if (reader && reader->has_room()) {
		for (const Vec2 &p : reader->get_room().floorplan.points) {
			points.push_back(Vector2(real_t(p.x), real_t(p.y)));
		}
	}
	return points;
}

double RigCapture::get_room_ceiling_height() const {
	return reader && reader->has_room() ? reader->get_room().floorplan.ceiling_height_m : 0.0;
}

PackedVector3Array RigCapture::get_probe_positions() const {
	PackedVector3Array out;
	if (reader && reader->has_room()) {
		for (const glm::dvec3 &p : reader->get_room().probes) {
			out.push_back(Vector3(real_t(p.x), real_t(p.y), real_t(p.z)));
		}
	}
	return out;
}

bool RigCapture::has_ground_truth() const {
	return reader && reader->has_ground_truth_trajectory(RecordingStream::Rgbd);
}

Transform3D RigCapture::get_ground_truth_camera_transform() const {
	Pose pose;
	std::string error;
	if (!has_ground_truth() || frame_index[STREAM_RGBD] < 0 ||
			!reader->ground_truth_trajectory(RecordingStream::Rgbd).pose_at(rgbd_frame.timestamp_s, &pose, &error)) {
		return Transform3D();
	}
	return camera_transform_from_pose(pose);
}

double RigCapture::get_rgb_camera_fov() const {
	if (!reader) {
		return 0.0;
	}
	const PinholeParams &rgb = reader->get_rig().rgb;
	return rgb.fy > 0.0 ? 2.0 * std::atan(0.5 * rgb.height / rgb.fy) * 180.0 / 3.14159265358979323846 : 0.0;
}

PackedStringArray RigCapture::get_warnings() const {
	PackedStringArray warnings;
	if (recording_path.is_empty()) {
		warnings.push_back("Set recording_path to a recording folder (docs/recording-format.md). Live devices are not supported yet.");
	}
	if (!last_error.empty()) {
		warnings.push_back(String(("The recording cannot be played: " + last_error).c_str()));
	}
	return warnings;
}

void RigCapture::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &RigCapture::get_warnings);
	ClassDB::bind_method(D_METHOD("set_recording_path", "path"), &RigCapture::set_recording_path);
	ClassDB::bind_method(D_METHOD("get_recording_path"), &RigCapture::get_recording_path);
	ClassDB::bind_method(D_METHOD("set_pacing", "pacing"), &RigCapture::set_pacing);
	ClassDB::bind_method(D_METHOD("get_pacing"), &RigCapture::get_pacing);
	ClassDB::bind_method(D_METHOD("set_loop", "loop"), &RigCapture::set_loop);
	ClassDB::bind_method(D_METHOD("get_loop"), &RigCapture::get_loop);
	ClassDB::bind_method(D_METHOD("set_autoplay", "autoplay"), &RigCapture::set_autoplay);
	ClassDB::bind_method(D_METHOD("get_autoplay"), &RigCapture::get_autoplay);
	ClassDB::bind_method(D_METHOD("open"), &RigCapture::open);
	ClassDB::bind_method(D_METHOD("close"), &RigCapture::close);
	ClassDB::bind_method(D_METHOD("is_open"), &RigCapture::is_open);
	ClassDB::bind_method(D_METHOD("play"), &RigCapture::play);
	ClassDB::bind_method(D_METHOD("stop"), &RigCapture::stop);
	ClassDB::bind_method(D_METHOD("is_playing"), &RigCapture::is_playing);
	ClassDB::bind_method(D_METHOD("step"), &RigCapture::step);
	ClassDB::bind_method(D_METHOD("rewind"), &RigCapture::rewind);
	ClassDB::bind_method(D_METHOD("get_frame_count", "stream"), &RigCapture::get_frame_count);
	ClassDB::bind_method(D_METHOD("get_event_count"), &RigCapture::get_event_count);
	ClassDB::bind_method(D_METHOD("get_event_position"), &RigCapture::get_event_position);
	ClassDB::bind_method(D_METHOD("get_time"), &RigCapture::get_time);
	ClassDB::bind_method(D_METHOD("get_frame_index", "stream"), &RigCapture::get_frame_index);
	ClassDB::bind_method(D_METHOD("get_frame_timestamp", "stream"), &RigCapture::get_frame_timestamp);
	ClassDB::bind_method(D_METHOD("get_dropped_frame_count"), &RigCapture::get_dropped_frame_count);
	ClassDB::bind_method(D_METHOD("get_rgb_texture"), &RigCapture::get_rgb_texture);
	ClassDB::bind_method(D_METHOD("get_depth_texture"), &RigCapture::get_depth_texture);
	ClassDB::bind_method(D_METHOD("get_fisheye_texture"), &RigCapture::get_fisheye_texture);
	ClassDB::bind_method(D_METHOD("get_rgb_image"), &RigCapture::get_rgb_image);
	ClassDB::bind_method(D_METHOD("get_depth_image"), &RigCapture::get_depth_image);
	ClassDB::bind_method(D_METHOD("get_fisheye_image"), &RigCapture::get_fisheye_image);
	ClassDB::bind_method(D_METHOD("get_issues"), &RigCapture::get_issues);
	ClassDB::bind_method(D_METHOD("get_last_error"), &RigCapture::get_last_error);
	ClassDB::bind_method(D_METHOD("get_room_floorplan"), &RigCapture::get_room_floorplan);
	ClassDB::bind_method(D_METHOD("get_room_ceiling_height"), &RigCapture::get_room_ceiling_height);
	ClassDB::bind_method(D_METHOD("get_probe_positions"), &RigCapture::get_probe_positions);
	ClassDB::bind_method(D_METHOD("has_ground_truth"), &RigCapture::has_ground_truth);
	ClassDB::bind_method(D_METHOD("get_ground_truth_camera_transform"), &RigCapture::get_ground_truth_camera_transform);
	ClassDB::bind_method(D_METHOD("get_rgb_camera_fov"), &RigCapture::get_rgb_camera_fov);

	ADD_PROPERTY(PropertyInfo(Variant::STRING, "recording_path", PROPERTY_HINT_GLOBAL_DIR), "set_recording_path", "get_recording_path");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "pacing", PROPERTY_HINT_ENUM, "Real Time,Step"), "set_pacing", "get_pacing");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "loop"), "set_loop", "get_loop");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "autoplay"), "set_autoplay", "get_autoplay");

	BIND_ENUM_CONSTANT(PACING_REAL_TIME);
	BIND_ENUM_CONSTANT(PACING_STEP);
	BIND_ENUM_CONSTANT(STREAM_RGBD);
	BIND_ENUM_CONSTANT(STREAM_FISHEYE);

	ADD_SIGNAL(MethodInfo("frame_captured", PropertyInfo(Variant::INT, "stream"), PropertyInfo(Variant::INT, "index"), PropertyInfo(Variant::FLOAT, "timestamp")));
	ADD_SIGNAL(MethodInfo("finished"));
}

} // namespace roomprobe
