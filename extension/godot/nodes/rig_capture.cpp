// RigCapture's lifecycle and playback of a recording: open, play, step, the frame clock, and the
// frames handed from the capture threads to the main thread.
#include "rig_capture.h"

#include "../convert/image_convert.h"
#include "../convert/project_paths.h"

#include <engine/engine_config.h>

using namespace godot;

namespace roomprobe {

RigCapture::RigCapture() :
		engine(std::make_shared<LiveRoom>()) {
	set_process_priority(-30);
	// Until a recording is open, the engine has no rig; the other nodes add their parts.
	engine->edit_config([](LiveRoomConfig &p_config) {
		p_config.has_rig = false;
		p_config.dense = false;
		p_config.has_room = false;
		p_config.display_buffers = packed_bytes_buffers();
	});
}

RigCapture::~RigCapture() {
	release_camera_feed();
	player.stop();
	live.reset(); // its sinks reach the engine and this node
	if (engine) {
		engine->stop();
	}
}

int64_t RigCapture::get_main_thread_usec() {
	return int64_t(MainThreadTimer::total_usec());
}

Dictionary RigCapture::get_main_thread_times() {
	Dictionary times;
	times["wall_usec"] = int64_t(MainThreadTimer::total_usec());
	times["cpu_usec"] = int64_t(MainThreadTimer::total_cpu_usec());
	for (int n = 0; n < MainThreadTimer::NODE_COUNT; n++) {
		const auto node = MainThreadTimer::Node(n);
		times[MainThreadTimer::node_class(node)] = int64_t(MainThreadTimer::node_usec(node));
	}
	return times;
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
	RecordingPlayer opened;
	std::string error = open_player(folder, PlayerOptions(), &opened);
	// Read before the engine is touched: a photometry file that cannot be read leaves it as it was.
	RigPhotometry photometry;
	if (error.empty()) {
		read_recording_photometry(folder, opened.reader().get_rig().photometry, &photometry, &error);
	}
	if (!error.empty()) {
		fail(error);
		return false;
	}
	player.open(std::move(opened));
	engine->edit_config([&](LiveRoomConfig &p_config) { config_from_recording(player.recording().reader(), photometry, false, &p_config); });
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

void RigCapture::close() {
	stop();
	if (live_open) {
		live.reset();
		live_open = false;
		has_live_room = false;
		engine->edit_config([](LiveRoomConfig &p_config) { p_config.has_rig = false; });
	}
	if (player.is_open()) {
		engine->edit_config([](LiveRoomConfig &p_config) {
			p_config.has_rig = false;
			p_config.ground_truth.clear();
		});
	}
	player.open(RecordingPlayer());
	rewind();
}

bool RigCapture::is_open() const { return player.is_open() || live_open; }

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
		player.start(PacedOptions(), [this](SourceFrame &&p_frame) { deliver_recorded(std::move(p_frame)); });
	}
	set_process(pacing == PACING_REAL_TIME);
}

void RigCapture::stop() {
	playing = false;
	player.stop();
	if (live) {
		stop_recording(); // no more frames: the recording is finished
		live->stop();
		release_camera_feed();
		feed_frames.reset();
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
		// Cleared before the player moves, so that no frame of the new pass is lost.
		const std::lock_guard<std::mutex> lock(mutex);
		latest = Shown();
	}
	player.rewind();
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

void RigCapture::deliver(bool p_is_rgbd, RgbdFrame &&p_rgbd, FisheyeFrame &&p_fisheye, int64_t p_index) {
	if (p_is_rgbd) {
		engine->push_rgbd(p_rgbd);
	} else {
		engine->push_fisheye(p_fisheye);
	}
	const int s = p_is_rgbd ? STREAM_RGBD : STREAM_FISHEYE;
	const std::lock_guard<std::mutex> lock(mutex);
	if (p_is_rgbd) {
		latest.rgbd = std::move(p_rgbd);
	} else {
		latest.fisheye = std::move(p_fisheye);
	}
	latest.index[s] = p_index >= 0 ? p_index : live_frames[s]++;
	latest.version[s]++;
}

// The player's capture thread (Real Time) or step() (Step). A frame that cannot be read is
// skipped with a warning, which the main thread prints.
void RigCapture::deliver_recorded(SourceFrame &&p_frame) {
	if (!p_frame.ok) {
		const std::lock_guard<std::mutex> lock(mutex);
		frame_warnings.push_back(p_frame.error);
		return;
	}
	deliver(p_frame.event.stream == RecordingStream::Rgbd, std::move(p_frame.rgbd), std::move(p_frame.fisheye), int64_t(p_frame.event.index));
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
	MainThreadTimer timer(MainThreadTimer::RIG_CAPTURE);
	if (source == SOURCE_LIVE) {
		fail("step() plays recordings one frame at a time; with source Live the devices stream (play())");
		return false;
	}
	if (!player.is_open() && !open()) {
		return false;
	}
	if (player.is_running()) {
		return false; // playing in real time: the capture thread reads
	}
	engine->apply_config();
	SourceFrame frame = player.step(loop);
	if (!frame.ok && frame.error == "end") {
		return false; // at the end without loop, or nothing to play
	}
	deliver_recorded(std::move(frame));
	show_frames(true);
	if (player.at_end()) {
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
	MainThreadTimer timer(MainThreadTimer::RIG_CAPTURE);
	if (engine->config_pending()) {
		// A node changed its part: the engine restarts with it (workers too, if they ran).
		engine->apply_config();
		update_configuration_warnings();
	}
	report_device_states();
	if (playing && live_open) {
		poll_camera_feed();
		show_frames(true);
		return;
	}
	if (!playing || !player.is_open() || pacing != PACING_REAL_TIME) {
		return;
	}
	// Whether the end was reached before this frame: its last frames are shown first.
	const bool at_end = player.reached_end();
	player.advance(p_delta);
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

} // namespace roomprobe
