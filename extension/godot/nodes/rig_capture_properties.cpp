// RigCapture's properties and its binding to Godot.
#include "rig_capture.h"

#include "../property_checks.h"

using namespace godot;

namespace roomprobe {

void RigCapture::set_recording_path(const String &p_path) {
	recording_path = p_path;
	last_error.clear(); // the error was about the previous recording
	checked_recording.clear();
	close();
	update_configuration_warnings();
}

String RigCapture::get_recording_path() const { return recording_path; }
void RigCapture::set_pacing(int64_t p_pacing) {
	if (property_checks::enum_in_range("RigCapture.pacing", p_pacing, 2)) {
		pacing = Pacing(p_pacing);
	}
}
RigCapture::Pacing RigCapture::get_pacing() const { return pacing; }
void RigCapture::set_loop(bool p_loop) { loop = p_loop; }
bool RigCapture::get_loop() const { return loop; }
void RigCapture::set_autoplay(bool p_autoplay) { autoplay = p_autoplay; }
bool RigCapture::get_autoplay() const { return autoplay; }

void RigCapture::set_source(int64_t p_source) {
	if (!property_checks::enum_in_range("RigCapture.source (0 Recording, 1 Live)", p_source, 2)) {
		return;
	}
	if (p_source == source) {
		return;
	}
	close();
	source = Source(p_source);
	last_error.clear();
	update_configuration_warnings();
}

RigCapture::Source RigCapture::get_source() const { return source; }

void RigCapture::set_rig_file(const String &p_path) {
	rig_file = p_path;
	last_error.clear();
	checked_rig.clear();
	if (source == SOURCE_LIVE) {
		close();
	}
	update_configuration_warnings();
}

String RigCapture::get_rig_file() const { return rig_file; }

void RigCapture::set_room_file(const String &p_path) {
	room_file = p_path;
	last_error.clear();
	if (source == SOURCE_LIVE) {
		close();
	}
	update_configuration_warnings();
}

String RigCapture::get_room_file() const { return room_file; }
// The device settings take effect at the next play().
void RigCapture::set_rgbd_device(const String &p_uri) { rgbd_device = p_uri; }
String RigCapture::get_rgbd_device() const { return rgbd_device; }
void RigCapture::set_fisheye_device(const String &p_id) { fisheye_device = p_id; }
String RigCapture::get_fisheye_device() const { return fisheye_device; }

void RigCapture::set_fisheye_backend(int64_t p_backend) {
	if (!property_checks::enum_in_range("RigCapture.fisheye_backend (0 Aravis, 1 UVC, 2 Camera Feed)", p_backend, 3)) {
		return;
	}
	fisheye_backend = FisheyeBackend(p_backend);
}

RigCapture::FisheyeBackend RigCapture::get_fisheye_backend() const { return fisheye_backend; }

void RigCapture::set_compute_backend(int64_t p_backend) {
	if (!property_checks::enum_in_range("RigCapture.compute_backend (0 CPU, 1 Vulkan, 2 Auto)", p_backend, 3)) {
		return;
	}
	compute_backend = ComputeBackendMode(p_backend);
	engine->edit_config([this](LiveRoomConfig &p_config) { p_config.compute_backend = ComputeBackend(compute_backend); });
	update_configuration_warnings();
}

RigCapture::ComputeBackendMode RigCapture::get_compute_backend() const { return compute_backend; }
void RigCapture::set_fisheye_pixel_format(const String &p_format) { fisheye_pixel_format = p_format; }
String RigCapture::get_fisheye_pixel_format() const { return fisheye_pixel_format; }
void RigCapture::set_auto_exposure(bool p_on) { auto_exposure = p_on; }
bool RigCapture::get_auto_exposure() const { return auto_exposure; }

void RigCapture::set_exposure_us(double p_exposure_us) {
	exposure_us = property_checks::clamped("RigCapture.exposure_us", p_exposure_us, 1.0, 10e6, exposure_us, " us");
}

double RigCapture::get_exposure_us() const { return exposure_us; }

void RigCapture::set_gain(double p_gain) {
	gain = property_checks::clamped("RigCapture.gain", p_gain, 0.0, 100.0, gain);
}

double RigCapture::get_gain() const { return gain; }

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
	ClassDB::bind_method(D_METHOD("set_source", "source"), &RigCapture::set_source);
	ClassDB::bind_method(D_METHOD("get_source"), &RigCapture::get_source);
	ClassDB::bind_method(D_METHOD("set_rig_file", "path"), &RigCapture::set_rig_file);
	ClassDB::bind_method(D_METHOD("get_rig_file"), &RigCapture::get_rig_file);
	ClassDB::bind_method(D_METHOD("set_room_file", "path"), &RigCapture::set_room_file);
	ClassDB::bind_method(D_METHOD("get_room_file"), &RigCapture::get_room_file);
	ClassDB::bind_method(D_METHOD("set_rgbd_device", "uri"), &RigCapture::set_rgbd_device);
	ClassDB::bind_method(D_METHOD("get_rgbd_device"), &RigCapture::get_rgbd_device);
	ClassDB::bind_method(D_METHOD("set_fisheye_device", "id"), &RigCapture::set_fisheye_device);
	ClassDB::bind_method(D_METHOD("get_fisheye_device"), &RigCapture::get_fisheye_device);
	ClassDB::bind_method(D_METHOD("set_compute_backend", "backend"), &RigCapture::set_compute_backend);
	ClassDB::bind_method(D_METHOD("get_compute_backend"), &RigCapture::get_compute_backend);
	ClassDB::bind_method(D_METHOD("set_fisheye_backend", "backend"), &RigCapture::set_fisheye_backend);
	ClassDB::bind_method(D_METHOD("get_fisheye_backend"), &RigCapture::get_fisheye_backend);
	ClassDB::bind_method(D_METHOD("_camera_feed_frame"), &RigCapture::_camera_feed_frame);
	ClassDB::bind_method(D_METHOD("set_fisheye_pixel_format", "format"), &RigCapture::set_fisheye_pixel_format);
	ClassDB::bind_method(D_METHOD("get_fisheye_pixel_format"), &RigCapture::get_fisheye_pixel_format);
	ClassDB::bind_method(D_METHOD("set_auto_exposure", "on"), &RigCapture::set_auto_exposure);
	ClassDB::bind_method(D_METHOD("get_auto_exposure"), &RigCapture::get_auto_exposure);
	ClassDB::bind_method(D_METHOD("set_exposure_us", "exposure_us"), &RigCapture::set_exposure_us);
	ClassDB::bind_method(D_METHOD("get_exposure_us"), &RigCapture::get_exposure_us);
	ClassDB::bind_method(D_METHOD("set_gain", "gain"), &RigCapture::set_gain);
	ClassDB::bind_method(D_METHOD("get_gain"), &RigCapture::get_gain);
	ClassDB::bind_method(D_METHOD("get_device_state", "stream"), &RigCapture::get_device_state);
	ClassDB::bind_method(D_METHOD("get_device_state_reason", "stream"), &RigCapture::get_device_state_reason);
	ClassDB::bind_method(D_METHOD("get_device_status", "stream"), &RigCapture::get_device_status);
	ClassDB::bind_method(D_METHOD("start_recording", "folder"), &RigCapture::start_recording);
	ClassDB::bind_method(D_METHOD("stop_recording"), &RigCapture::stop_recording);
	ClassDB::bind_method(D_METHOD("is_recording"), &RigCapture::is_recording);
	ClassDB::bind_method(D_METHOD("get_recording_status"), &RigCapture::get_recording_status);
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
	ClassDB::bind_static_method("RigCapture", D_METHOD("get_main_thread_usec"), &RigCapture::get_main_thread_usec);
	ClassDB::bind_static_method("RigCapture", D_METHOD("get_main_thread_times"), &RigCapture::get_main_thread_times);
	bind_properties();
}

void RigCapture::bind_properties() {
	ADD_PROPERTY(PropertyInfo(Variant::INT, "source", PROPERTY_HINT_ENUM, "Recording,Live"), "set_source", "get_source");
	ADD_GROUP("Recording", "");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "recording_path", PROPERTY_HINT_GLOBAL_DIR), "set_recording_path", "get_recording_path");
	ADD_GROUP("Live", "");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "rig_file", PROPERTY_HINT_FILE, "*.yaml"), "set_rig_file", "get_rig_file");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "room_file", PROPERTY_HINT_FILE, "*.yaml"), "set_room_file", "get_room_file");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "rgbd_device"), "set_rgbd_device", "get_rgbd_device");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "fisheye_device"), "set_fisheye_device", "get_fisheye_device");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "fisheye_backend", PROPERTY_HINT_ENUM, "Aravis,UVC,Camera Feed"), "set_fisheye_backend", "get_fisheye_backend");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "fisheye_pixel_format"), "set_fisheye_pixel_format", "get_fisheye_pixel_format");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "auto_exposure"), "set_auto_exposure", "get_auto_exposure");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "exposure_us", PROPERTY_HINT_RANGE, "1,10000000,1,suffix:us"), "set_exposure_us", "get_exposure_us");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "gain", PROPERTY_HINT_RANGE, "0,100,0.1"), "set_gain", "get_gain");
	ADD_GROUP("Compute", "");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "compute_backend", PROPERTY_HINT_ENUM, "CPU,Vulkan,Auto"), "set_compute_backend", "get_compute_backend");
	ADD_GROUP("Playback", "");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "pacing", PROPERTY_HINT_ENUM, "Real Time,Step"), "set_pacing", "get_pacing");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "loop"), "set_loop", "get_loop");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "autoplay"), "set_autoplay", "get_autoplay");

	BIND_ENUM_CONSTANT(PACING_REAL_TIME);
	BIND_ENUM_CONSTANT(PACING_STEP);
	BIND_ENUM_CONSTANT(STREAM_RGBD);
	BIND_ENUM_CONSTANT(STREAM_FISHEYE);
	BIND_ENUM_CONSTANT(SOURCE_RECORDING);
	BIND_ENUM_CONSTANT(SOURCE_LIVE);
	BIND_ENUM_CONSTANT(FISHEYE_BACKEND_ARAVIS);
	BIND_ENUM_CONSTANT(FISHEYE_BACKEND_UVC);
	BIND_ENUM_CONSTANT(FISHEYE_BACKEND_CAMERA_FEED);
	BIND_ENUM_CONSTANT(COMPUTE_BACKEND_CPU);
	BIND_ENUM_CONSTANT(COMPUTE_BACKEND_VULKAN);
	BIND_ENUM_CONSTANT(COMPUTE_BACKEND_AUTO);
	BIND_ENUM_CONSTANT(DEVICE_STATE_STOPPED);
	BIND_ENUM_CONSTANT(DEVICE_STATE_CONNECTING);
	BIND_ENUM_CONSTANT(DEVICE_STATE_STREAMING);
	BIND_ENUM_CONSTANT(DEVICE_STATE_STALLED);
	BIND_ENUM_CONSTANT(DEVICE_STATE_DISCONNECTED);

	ADD_SIGNAL(MethodInfo("frame_captured", PropertyInfo(Variant::INT, "stream"), PropertyInfo(Variant::INT, "index"), PropertyInfo(Variant::FLOAT, "timestamp")));
	ADD_SIGNAL(MethodInfo("finished"));
	ADD_SIGNAL(MethodInfo("device_state_changed", PropertyInfo(Variant::INT, "stream"), PropertyInfo(Variant::INT, "state"), PropertyInfo(Variant::STRING, "reason")));
}

} // namespace roomprobe
