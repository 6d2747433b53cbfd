#include "rig_capture.h"

#include "../property_checks.h"

#include <camera/pinhole_camera.h>

#include "../convert/image_convert.h"
#include "../convert/pose_convert.h"
#include "../convert/project_paths.h"

#include <recording/room_file.h>
#include <rig/photometry.h>
#include <room/room_from_sweep.h>

#include <cmath>
#include <filesystem>

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
	if (!property_checks::enum_in_range("RigCapture.fisheye_backend (0 Aravis, 1 UVC)", p_backend, 2)) {
		return;
	}
	fisheye_backend = FisheyeBackend(p_backend);
}

RigCapture::FisheyeBackend RigCapture::get_fisheye_backend() const { return fisheye_backend; }
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

RigCapture::RigCapture() :
		engine(std::make_shared<LiveRoom>()) {
	set_process_priority(-30);
	// Until a recording is open, the engine has no rig; the other nodes add their parts.
	engine->edit_config([](LiveRoomConfig &p_config) {
		p_config.has_rig = false;
		p_config.dense = false;
		p_config.has_room = false;
	});
}

RigCapture::~RigCapture() {
	stop_capture();
	live.reset(); // its sinks reach the engine and this node
	if (engine) {
		engine->stop();
	}
}

int64_t RigCapture::get_main_thread_usec() {
	return int64_t(MainThreadTimer::total_usec());
}

void RigCapture::fail(const std::string &p_message) {
	last_error = p_message;
	ERR_PRINT(String(("RigCapture: " + p_message).c_str()));
	update_configuration_warnings();
}

bool RigCapture::open() {
	if (source == SOURCE_LIVE) {
		return open_live();
	}
	close();
	if (recording_path.is_empty()) {
		fail("recording_path is empty");
		return false;
	}
	// res:// and user:// paths work as well as absolute ones, and a zipped recording (in a pack too).
	std::string folder;
	if (!path_on_disk("recording_path", recording_path, &folder)) {
		return false;
	}
	auto opened = std::make_shared<RecordingReader>();
	const RecordingStatus status = opened->open(folder);
	if (!status.ok) {
		fail(status.error);
		return false;
	}
	RigPhotometry photometry;
	std::string error;
	if (!read_recording_photometry(folder, opened->get_rig().photometry, &photometry, &error)) {
		fail(error);
		return false;
	}
	reader = opened;
	engine->edit_config([&](LiveRoomConfig &p_config) {
		p_config.has_rig = true;
		p_config.rig = opened->get_rig();
		p_config.photometry = photometry;
		p_config.initial_rgb_pose = opened->has_room() ? opened->get_room().initial_rgb_pose
														: upright_first_rgb_pose(opened->get_rig().has_fisheye(), opened->get_rig().rgb_from_fisheye);
		p_config.keep_points = opened->has_room() ? opened->get_room().probes : std::vector<glm::dvec3>();
		p_config.ground_truth = opened->has_ground_truth_trajectory(RecordingStream::Rgbd) ? opened->ground_truth_trajectory(RecordingStream::Rgbd) : Trajectory();
	});
	last_error.clear();
	update_configuration_warnings();
	return true;
}

// p_value, the path property p_property, as a path on disk (convert/project_paths); false, having
// failed with the property's name, when it cannot be.
bool RigCapture::path_on_disk(const char *p_property, const String &p_value, std::string *r_path) {
	std::string error;
	*r_path = disk_path_for(p_value, &error);
	if (!error.empty()) {
		fail(std::string(p_property) + " " + error);
		return false;
	}
	return true;
}

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
	engine->edit_config([&](LiveRoomConfig &p_config) {
		p_config.has_rig = true;
		p_config.rig = live_rig;
		p_config.photometry = live_rig.photometry; // unknown for a rig file without photometry (version 1)
		p_config.initial_rgb_pose = has_live_room ? live_room.initial_rgb_pose : upright_first_rgb_pose(live_rig.has_fisheye(), live_rig.rgb_from_fisheye);
		p_config.keep_points = has_live_room ? live_room.probes : std::vector<glm::dvec3>();
		p_config.ground_truth.clear();
	});
	last_error.clear();
	update_configuration_warnings();
	return true;
}

void RigCapture::close() {
	stop();
	if (live_open) {
		live.reset();
		live_open = false;
		has_live_room = false;
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.has_rig = false; });
	}
	if (reader) {
		engine->edit_config([](LiveRoomConfig &p_config) {
			p_config.has_rig = false;
			p_config.ground_truth.clear();
		});
	}
	reader.reset();
	rewind();
}

bool RigCapture::is_open() const { return reader != nullptr || live_open; }

void RigCapture::play() {
	if (!is_open() && !open()) {
		return;
	}
	playing = true;
	if (live_open) {
		engine->apply_config();
		engine->start();
		start_live();
		set_process(playing);
		return;
	}
	if (pacing == PACING_REAL_TIME) {
		// The engine's workers take the frames; the capture thread reads them.
		engine->apply_config();
		engine->start();
		start_capture();
	}
	set_process(pacing == PACING_REAL_TIME);
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
	{
		const std::lock_guard<std::mutex> lock(mutex);
		live_frames[0] = live_frames[1] = 0;
	}
	const std::string error = live->start(
			live_rig, settings,
			[this](drivers::CapturedFrame &&p_frame) {
				const int s = p_frame.is_rgbd ? STREAM_RGBD : STREAM_FISHEYE;
				if (p_frame.is_rgbd) {
					engine->push_rgbd(p_frame.rgbd);
				} else {
					engine->push_fisheye(p_frame.fisheye);
				}
				const std::lock_guard<std::mutex> lock(mutex);
				if (p_frame.is_rgbd) {
					latest.rgbd = std::move(p_frame.rgbd);
				} else {
					latest.fisheye = std::move(p_frame.fisheye);
				}
				latest.index[s] = live_frames[s]++;
				latest.version[s]++;
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

void RigCapture::stop() {
	playing = false;
	stop_capture();
	if (live) {
		stop_recording(); // no more frames: the recording is finished
		live->stop();
		for (drivers::DeviceStatus &status : device_status) {
			status = drivers::DeviceStatus();
		}
	}
	engine->stop();
	set_process(false);
}

bool RigCapture::is_playing() const { return playing; }

void RigCapture::rewind() {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		next_event = 0;
		clock_s = 0.0;
		dropped = 0;
		reached_end = false;
		latest = Shown();
	}
	clock_advanced.notify_all();
	frame_index[0] = frame_index[1] = -1;
	shown_version[0] = shown_version[1] = 0;
}

void RigCapture::_notification(int p_what) {
	if (p_what == NOTIFICATION_EXIT_TREE) {
		// Frames stop with the scene; the engine keeps its model for the nodes still holding it.
		if (playing) {
			stop();
		}
	}
}

// Reads the frame of event p_event and hands it to the engine and to the main thread. Called by
// the capture thread (Real Time) or by step() (Step). False when the frame cannot be read.
bool RigCapture::read_event(size_t p_event) {
	const PlaybackEvent event = reader->get_events()[p_event];
	if (event.stream == RecordingStream::Rgbd) {
		RgbdFrameResult result = reader->read_rgbd(event.index);
		if (!result.ok) {
			const std::lock_guard<std::mutex> lock(mutex);
			frame_warnings.push_back(result.error);
			return false;
		}
		engine->push_rgbd(result.frame);
		const std::lock_guard<std::mutex> lock(mutex);
		latest.rgbd = std::move(result.frame);
		latest.index[STREAM_RGBD] = int64_t(event.index);
		latest.version[STREAM_RGBD]++;
	} else {
		FisheyeFrameResult result = reader->read_fisheye(event.index);
		if (!result.ok) {
			const std::lock_guard<std::mutex> lock(mutex);
			frame_warnings.push_back(result.error);
			return false;
		}
		engine->push_fisheye(result.frame);
		const std::lock_guard<std::mutex> lock(mutex);
		latest.fisheye = std::move(result.frame);
		latest.index[STREAM_FISHEYE] = int64_t(event.index);
		latest.version[STREAM_FISHEYE]++;
	}
	return true;
}

void RigCapture::capture_loop() {
	const std::vector<PlaybackEvent> &events = reader->get_events();
	std::unique_lock<std::mutex> lock(mutex);
	while (!capture_stop) {
		if (next_event >= events.size()) {
			reached_end = true; // the main thread signals it, and rewinds when looping
			clock_advanced.wait(lock, [this, &events] { return capture_stop || next_event < events.size(); });
			continue;
		}
		// Of the frames now due, only the newest of each stream is read: a slow reader drops
		// frames instead of falling ever further behind.
		size_t due_end = next_event;
		while (due_end < events.size() && events[due_end].time_s - events.front().time_s <= clock_s) {
			due_end++;
		}
		if (due_end == next_event) {
			clock_advanced.wait(lock);
			continue;
		}
		std::vector<size_t> to_read;
		for (size_t e = next_event; e < due_end; e++) {
			bool newest = true;
			for (size_t later = e + 1; later < due_end; later++) {
				newest = newest && events[later].stream != events[e].stream;
			}
			if (newest) {
				to_read.push_back(e);
			} else {
				dropped++;
			}
		}
		next_event = due_end;
		lock.unlock();
		for (size_t e : to_read) {
			read_event(e);
		}
		lock.lock();
	}
}

void RigCapture::start_capture() {
	stop_capture();
	{
		const std::lock_guard<std::mutex> lock(mutex);
		capture_stop = false;
	}
	capture_thread = std::thread([this] { capture_loop(); });
}

void RigCapture::stop_capture() {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		capture_stop = true;
	}
	clock_advanced.notify_all();
	if (capture_thread.joinable()) {
		capture_thread.join();
	}
}

// Main thread: takes the newest frames read since the last call, shows them where wanted and
// signals them.
void RigCapture::show_frames(bool p_signal) {
	Shown taken;
	std::vector<std::string> warnings;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		taken = latest; // cv::Mat copies share pixels that nobody writes again
		warnings.swap(frame_warnings);
	}
	for (const std::string &w : warnings) {
		// One bad frame is skipped; playback goes on.
		WARN_PRINT(String(("RigCapture: " + w).c_str()));
	}
	bool changed[2] = { false, false };
	for (int s = 0; s < 2; s++) {
		changed[s] = taken.version[s] != shown_version[s] && taken.index[s] >= 0;
		shown_version[s] = taken.version[s];
		frame_index[s] = taken.index[s];
	}
	if (changed[STREAM_RGBD]) {
		rgbd_frame = taken.rgbd;
	}
	if (changed[STREAM_FISHEYE]) {
		fisheye_frame = taken.fisheye;
	}
	if (!changed[0] && !changed[1]) {
		return;
	}
	images_stale = true;
	if (textures_wanted) {
		// Only textures someone asked for cost main-thread time.
		update_textures(changed[STREAM_RGBD], changed[STREAM_FISHEYE]);
	}
	if (p_signal) {
		for (int s = 0; s < 2; s++) {
			if (changed[s]) {
				emit_signal("frame_captured", s, frame_index[s], s == STREAM_RGBD ? rgbd_frame.timestamp_s : fisheye_frame.timestamp_s);
			}
		}
	}
}

bool RigCapture::step() {
	MainThreadTimer timer;
	if (source == SOURCE_LIVE) {
		fail("step() plays recordings one frame at a time; with source Live the devices stream (play())");
		return false;
	}
	if (!reader && !open()) {
		return false;
	}
	if (capture_thread.joinable()) {
		return false; // playing in real time: the capture thread reads
	}
	engine->apply_config();
	const auto &events = reader->get_events();
	size_t event = 0;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		if (next_event >= events.size()) {
			if (!loop || events.empty()) {
				return false;
			}
			next_event = 0;
		}
		event = next_event++;
		clock_s = events[event].time_s - events.front().time_s;
	}
	read_event(event);
	show_frames(true);
	bool at_end = false;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		at_end = next_event >= events.size();
	}
	if (at_end) {
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
	MainThreadTimer timer;
	if (engine->config_pending()) {
		// A node changed its part: the engine restarts with it (workers too, if they ran).
		engine->apply_config();
		update_configuration_warnings();
	}
	report_device_states();
	if (playing && live_open) {
		show_frames(true);
		return;
	}
	if (!playing || !reader || pacing != PACING_REAL_TIME) {
		return;
	}
	bool at_end = false;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		clock_s += p_delta;
		at_end = reached_end;
	}
	clock_advanced.notify_all();
	show_frames(true);
	if (at_end) {
		emit_signal("finished");
		if (loop) {
			rewind();
		} else {
			stop();
		}
	}
}

int64_t RigCapture::get_frame_count(Stream p_stream) const {
	if (live_open) {
		const std::lock_guard<std::mutex> lock(mutex);
		return live_frames[p_stream == STREAM_RGBD ? 0 : 1];
	}
	if (!reader) {
		return 0;
	}
	return int64_t(p_stream == STREAM_RGBD ? reader->rgbd_count() : reader->fisheye_count());
}

int64_t RigCapture::get_event_count() const { return reader ? int64_t(reader->get_events().size()) : 0; }
int64_t RigCapture::get_event_position() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return int64_t(next_event);
}

double RigCapture::get_time() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return clock_s;
}
int64_t RigCapture::get_frame_index(Stream p_stream) const { return frame_index[p_stream == STREAM_RGBD ? 0 : 1]; }

double RigCapture::get_frame_timestamp(Stream p_stream) const {
	if (get_frame_index(p_stream) < 0) {
		return -1.0;
	}
	return p_stream == STREAM_RGBD ? rgbd_frame.timestamp_s : fisheye_frame.timestamp_s;
}

int64_t RigCapture::get_dropped_frame_count() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return dropped;
}

// The textures are made on first request and from then on follow the frames.
Ref<ImageTexture> RigCapture::get_rgb_texture() const {
	if (!textures_wanted) {
		textures_wanted = true;
		update_textures(frame_index[STREAM_RGBD] >= 0, frame_index[STREAM_FISHEYE] >= 0);
	}
	return rgb_texture;
}

void RigCapture::update_textures(bool p_rgbd, bool p_fisheye) const {
	if (p_rgbd) {
		show_in_texture(image_from_mat(rgbd_frame.rgb), rgb_texture);
		show_in_texture(image_from_mat(rgbd_frame.depth_m), depth_texture);
	}
	if (p_fisheye) {
		show_in_texture(image_from_mat(fisheye_frame.image), fisheye_texture);
	}
}

Ref<ImageTexture> RigCapture::get_depth_texture() const {
	get_rgb_texture();
	return depth_texture;
}

Ref<ImageTexture> RigCapture::get_fisheye_texture() const {
	get_rgb_texture();
	return fisheye_texture;
}

Ref<Image> RigCapture::get_rgb_image() const {
	if (images_stale) {
		rgb_image = frame_index[STREAM_RGBD] >= 0 ? image_from_mat(rgbd_frame.rgb) : Ref<Image>();
		depth_image = frame_index[STREAM_RGBD] >= 0 ? image_from_mat(rgbd_frame.depth_m) : Ref<Image>();
		fisheye_image = frame_index[STREAM_FISHEYE] >= 0 ? image_from_mat(fisheye_frame.image) : Ref<Image>();
		images_stale = false;
	}
	return rgb_image;
}

Ref<Image> RigCapture::get_depth_image() const {
	get_rgb_image();
	return depth_image;
}

Ref<Image> RigCapture::get_fisheye_image() const {
	get_rgb_image();
	return fisheye_image;
}

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

const RoomInfo *RigCapture::room_info() const {
	if (live_open) {
		return has_live_room ? &live_room : nullptr;
	}
	if (reader) {
		return reader->has_room() ? &reader->get_room() : nullptr;
	}
	return preview_room();
}

// Before the recording is opened (in the editor nothing opens it), a CoarseRoomModel with
// floorplan_source Recording should still show its room: the folder's room.yaml alone is read
// (not a zip's: that would unpack it).
const RoomInfo *RigCapture::preview_room() const {
	if (source != SOURCE_RECORDING || recording_path.is_empty() ||
			recording_path.to_lower().ends_with(".zip")) {
		return nullptr;
	}
	if (previewed_path != recording_path) {
		previewed_path = recording_path;
		has_preview_room = false;
		std::string error;
		const std::string folder = disk_path_for(recording_path, &error);
		if (error.empty() && !folder.empty()) {
			const RoomLoadResult loaded = load_room_file((std::filesystem::path(folder) / "room.yaml").string());
			has_preview_room = loaded.ok;
			preview = loaded.room;
		}
	}
	return has_preview_room ? &preview : nullptr;
}

const Rig *RigCapture::rig_info() const {
	return live_open ? &live_rig : reader ? &reader->get_rig() : nullptr;
}

PackedVector2Array RigCapture::get_room_floorplan() const {
	PackedVector2Array points;
	if (const RoomInfo *room = room_info()) {
		for (const Vec2 &p : room->floorplan.points) {
			points.push_back(Vector2(real_t(p.x), real_t(p.y)));
		}
	}
	return points;
}

double RigCapture::get_room_ceiling_height() const {
	const RoomInfo *room = room_info();
	return room ? room->floorplan.ceiling_height_m : 0.0;
}

PackedVector3Array RigCapture::get_probe_positions() const {
	PackedVector3Array out;
	if (const RoomInfo *room = room_info()) {
		for (const glm::dvec3 &p : room->probes) {
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
	const Rig *rig = rig_info();
	if (!rig) {
		return 0.0;
	}
	return pinhole_vertical_fov_degrees(rig->rgb);
}

PackedStringArray RigCapture::get_warnings() const {
	PackedStringArray warnings;
	if (source == SOURCE_RECORDING && recording_path.is_empty()) {
		warnings.push_back("Set recording_path to a recording folder (docs/recording-format.md), or set source to Live.");
	}
	if (source == SOURCE_LIVE && rig_file.is_empty()) {
		warnings.push_back("Set rig_file to the rig's calibration file (calib/README.md): source Live needs it.");
	}
	if (!last_error.empty()) {
		warnings.push_back(String(((source == SOURCE_LIVE ? "The live rig cannot run: " : "The recording cannot be played: ") + last_error).c_str()));
	} else if (source == SOURCE_RECORDING && !recording_path.is_empty() && !reader) {
		// Not opened yet (the editor): whether it would open, read once per path (indexes only).
		const std::string key = recording_path.utf8_string();
		if (key != checked_recording) {
			checked_recording = key;
			const std::string folder = disk_path_for(recording_path, &recording_problem);
			if (recording_problem.empty()) {
				const RecordingStatus status = RecordingReader().open(folder);
				recording_problem = status.ok ? "" : status.error;
			}
		}
		if (!recording_problem.empty()) {
			warnings.push_back(String(("recording_path cannot be played: " + recording_problem).c_str()));
		}
	} else if (source == SOURCE_LIVE && !rig_file.is_empty() && !live_open) {
		const std::string key = rig_file.utf8_string();
		if (key != checked_rig) {
			checked_rig = key;
			const std::string file = disk_path_for(rig_file, &rig_problem);
			if (rig_problem.empty()) {
				const RigLoadResult loaded = load_rig(file);
				rig_problem = loaded.ok ? "" : loaded.error;
			}
		}
		if (!rig_problem.empty()) {
			warnings.push_back(String(("rig_file cannot be read: " + rig_problem).c_str()));
		}
	}
	if (live_open && playing) {
		for (int s = 0; s < 2; s++) {
			const drivers::DeviceStatus &status = device_status[s];
			if (status.state == drivers::DeviceState::Stalled || status.state == drivers::DeviceState::Disconnected) {
				warnings.push_back(String(((s == STREAM_RGBD ? std::string("The RGB-D camera is ") : std::string("The fisheye is ")) +
						drivers::device_state_name(status.state) + ": " + status.reason).c_str()));
			}
		}
	}
	if ((reader || live_open) && !engine->config_pending() && !engine->configuration_error().empty()) {
		warnings.push_back(String(("The live engine is not running: " + engine->configuration_error()).c_str()));
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
	ClassDB::bind_method(D_METHOD("set_fisheye_backend", "backend"), &RigCapture::set_fisheye_backend);
	ClassDB::bind_method(D_METHOD("get_fisheye_backend"), &RigCapture::get_fisheye_backend);
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

	ADD_PROPERTY(PropertyInfo(Variant::INT, "source", PROPERTY_HINT_ENUM, "Recording,Live"), "set_source", "get_source");
	ADD_GROUP("Recording", "");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "recording_path", PROPERTY_HINT_GLOBAL_DIR), "set_recording_path", "get_recording_path");
	ADD_GROUP("Live", "");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "rig_file", PROPERTY_HINT_FILE, "*.yaml"), "set_rig_file", "get_rig_file");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "room_file", PROPERTY_HINT_FILE, "*.yaml"), "set_room_file", "get_room_file");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "rgbd_device"), "set_rgbd_device", "get_rgbd_device");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "fisheye_device"), "set_fisheye_device", "get_fisheye_device");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "fisheye_backend", PROPERTY_HINT_ENUM, "Aravis,UVC"), "set_fisheye_backend", "get_fisheye_backend");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "fisheye_pixel_format"), "set_fisheye_pixel_format", "get_fisheye_pixel_format");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "auto_exposure"), "set_auto_exposure", "get_auto_exposure");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "exposure_us", PROPERTY_HINT_RANGE, "1,10000000,1,suffix:us"), "set_exposure_us", "get_exposure_us");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "gain", PROPERTY_HINT_RANGE, "0,100,0.1"), "set_gain", "get_gain");
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
