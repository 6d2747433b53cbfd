// RigCapture with source Live: the devices' capture threads, their states, and recording them.
#include "rig_capture.h"

#include "../convert/project_paths.h"

#include <engine/engine_config.h>
#include <recording/room_file.h>

using namespace godot;

namespace roomprobe {

// Reads rig_file (and room_file) and gives the engine the rig; the devices start with play().
bool RigCapture::open_live() {
	close();
	if (rig_file.is_empty()) {
		fail("rig_file is empty: with source Live, set it to the rig's calibration file (calib/README.md)");
		return false;
	}
	std::string rig_path;
	if (!path_on_disk("rig_file", rig_file, &rig_path)) {
		return false;
	}
	const RigLoadResult loaded = load_rig(rig_path);
	if (!loaded.ok) {
		fail(loaded.error);
		return false;
	}
	RoomInfo room;
	if (!room_file.is_empty()) {
		std::string room_path;
		if (!path_on_disk("room_file", room_file, &room_path)) {
			return false;
		}
		const RoomLoadResult room_loaded = load_room_file(room_path);
		if (!room_loaded.ok) {
			fail(room_loaded.error);
			return false;
		}
		room = room_loaded.room;
	}
	live_rig = drivers::live_capture_rig(loaded.rig);
	has_live_room = !room_file.is_empty();
	live_room = room;
	live_open = true;
	engine->edit_config([this](LiveRoomConfig &p_config) {
		config_from_rig(live_rig, live_rig.photometry, has_live_room ? &live_room : nullptr, false, &p_config);
	});
	last_error.clear();
	update_configuration_warnings();
	return true;
}

// The devices' capture threads feed the engine and the node's newest frames; their state
// changes wait for the main thread (report_device_states).
void RigCapture::start_live() {
	if (!live) {
		live = std::make_unique<drivers::LiveRig>();
	}
	// A device may be a file played as if live (an .oni, a video): res:// and user:// work (a file in
	// an exported pack is copied out first); a path that cannot be is passed on, for the driver to name.
	const auto device_text = [](const String &p_value) {
		std::string error;
		const std::string path = disk_path_for(p_value, &error);
		return error.empty() ? path : p_value.utf8_string();
	};
	drivers::LiveRigSettings settings;
	settings.rgbd.uri = device_text(rgbd_device);
	settings.fisheye.device = device_text(fisheye_device);
	settings.fisheye.pixel_format = fisheye_pixel_format.utf8_string();
	settings.fisheye.auto_exposure = auto_exposure;
	settings.fisheye.exposure_us = exposure_us;
	settings.fisheye.gain = gain;
	settings.fisheye_backend = fisheye_backend == FISHEYE_BACKEND_UVC ? drivers::FisheyeBackend::Uvc : drivers::FisheyeBackend::Aravis;
	if (fisheye_backend == FISHEYE_BACKEND_CAMERA_FEED && live_rig.has_fisheye()) {
		// The main thread pushes the feed's frames (rig_capture_feed.cpp); found before the capture
		// thread first opens it, so an absent feed is its first reason.
		settings.fisheye_backend = drivers::FisheyeBackend::Pushed;
		settings.pushed_fisheye = start_camera_feed();
	}
	{
		const std::lock_guard<std::mutex> lock(mutex);
		live_frames[0] = live_frames[1] = 0;
	}
	const std::string error = live->start(
			live_rig, settings,
			[this](drivers::CapturedFrame &&p_frame) {
				deliver(p_frame.is_rgbd, std::move(p_frame.rgbd), std::move(p_frame.fisheye), -1);
			},
			[this](RecordingStream p_stream, const drivers::DeviceStatus &p_status) {
				const std::lock_guard<std::mutex> lock(mutex);
				state_changes.push_back({ p_stream == RecordingStream::Rgbd ? STREAM_RGBD : STREAM_FISHEYE, p_status });
			});
	if (!error.empty()) {
		playing = false;
		engine->stop();
		fail(error);
	}
}

void RigCapture::report_device_states() {
	std::vector<StateChange> changes;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		changes.swap(state_changes);
	}
	for (const StateChange &change : changes) {
		device_status[change.stream] = change.status;
		emit_signal("device_state_changed", int(change.stream), int(change.status.state), String(change.status.reason.c_str()));
	}
	if (!changes.empty()) {
		update_configuration_warnings();
	}
}

RigCapture::DeviceState RigCapture::get_device_state(Stream p_stream) const {
	return DeviceState(int(device_status[p_stream == STREAM_RGBD ? 0 : 1].state));
}

String RigCapture::get_device_state_reason(Stream p_stream) const {
	return String(device_status[p_stream == STREAM_RGBD ? 0 : 1].reason.c_str());
}

Dictionary RigCapture::get_device_status(Stream p_stream) const {
	const RecordingStream stream = p_stream == STREAM_RGBD ? RecordingStream::Rgbd : RecordingStream::Fisheye;
	const drivers::DeviceStatus status = live ? live->status(stream) : drivers::DeviceStatus();
	Dictionary d;
	d["device"] = String(live ? live->device_name(stream).c_str() : "");
	d["state"] = int(status.state);
	d["state_name"] = String(drivers::device_state_name(status.state));
	d["reason"] = String(status.reason.c_str());
	d["frames"] = int64_t(status.frames);
	d["reconnections"] = int64_t(status.reconnections);
	return d;
}

bool RigCapture::start_recording(const String &p_folder) {
	if (!live || !live->is_running()) {
		fail("start_recording(" + p_folder.utf8_string() + "): the live rig is not streaming; set source to Live and play() first "
																"(a recording is played back, not recorded again)");
		return false;
	}
	// An empty or relative path would land wherever the process's folder is (the project's, or
	// OpenNI2's drivers folder, which it changes to): say where to record instead.
	const std::string folder = ProjectSettings::get_singleton()->globalize_path(p_folder).utf8_string();
	if (folder.empty() || folder.front() != '/') {
		fail("start_recording(\"" + p_folder.utf8_string() + "\"): name the folder to record into, as an absolute path or under user://");
		return false;
	}
	const RecordingStatus status = live->start_recording(folder, has_live_room ? &live_room : nullptr);
	if (!status.ok) {
		fail(status.error);
		return false;
	}
	return true;
}

bool RigCapture::stop_recording() {
	if (!live) {
		return true;
	}
	const RecordingStatus status = live->stop_recording();
	if (!status.ok) {
		fail(status.error);
	}
	return status.ok;
}

bool RigCapture::is_recording() const { return live && live->is_recording(); }

Dictionary RigCapture::get_recording_status() const {
	const RecordingQueueStatus status = live ? live->recording_status() : RecordingQueueStatus();
	Dictionary d;
	d["recording"] = status.recording;
	d["folder"] = String(status.folder.c_str());
	d["rgbd_written"] = int64_t(status.written[0]);
	d["fisheye_written"] = int64_t(status.written[1]);
	d["rgbd_dropped"] = int64_t(status.dropped[0]);
	d["fisheye_dropped"] = int64_t(status.dropped[1]);
	d["gaps"] = int64_t(status.gaps);
	d["queued"] = int64_t(status.queued);
	d["seconds"] = status.seconds;
	d["megabytes"] = status.megabytes_written;
	d["megabytes_per_s"] = status.megabytes_per_s;
	d["error"] = String(status.error.c_str());
	return d;
}

} // namespace roomprobe
