// RigCapture's fisheye from a Godot camera feed (fisheye_backend Camera Feed, issue #43).
// CameraServer reaches cameras that RoomProbe's own drivers cannot: Android's cameras, a headset's
// passthrough, and V4L2 webcams in the packaged addon (which has no UVC backend). A feed hands its
// frames to the renderer only, so the main thread reads the newest back (CameraFeedReader) and
// pushes it to the fisheye's capture thread (drivers/capture/pushed_camera.h), stamped when the
// feed signalled it. Everything after that (states, latency, the engine, recording) is the live
// rig's, as for any fisheye.
#include "rig_capture.h"

#include <capture/capture_clock.h>

using namespace godot;

namespace roomprobe {

namespace {

std::string feed_label(const std::string &p_name) {
	return "Godot camera feed '" + p_name + "'";
}

} // namespace

void RigCapture::_camera_feed_frame() {
	// Stamped first: the frame reached the host now, whenever the main thread reads it.
	feed_arrival_ns.store(drivers::monotonic_clock_ns());
	feed_signals.fetch_add(1);
}

// Finds the feed fisheye_device names (its name or id; empty: the first) and connects to it; if
// it is followed already, checks that CameraServer still lists it (an unplugged webcam is not).
bool RigCapture::follow_camera_feed() {
	CameraServer *server = CameraServer::get_singleton();
	if (!server->is_monitoring_feeds()) {
		// Godot lists feeds only while monitoring (on Linux and macOS the system's cameras arrive
		// over the next frames).
		server->set_monitoring_feeds(true);
	}
	const std::string wanted = fisheye_device.utf8_string();
	std::vector<std::string> listed;
	Ref<CameraFeed> found;
	for (int64_t i = 0; i < server->get_feed_count() && found.is_null(); i++) {
		const Ref<CameraFeed> candidate = server->get_feed(i);
		if (candidate.is_null()) {
			continue;
		}
		const std::string name = candidate->get_name().utf8_string();
		const std::string id = std::to_string(candidate->get_id());
		if (feed.is_valid() ? candidate == feed : (wanted.empty() || wanted == name || wanted == id)) {
			found = candidate;
		}
		listed.push_back("'" + name + "' (id " + id + ")");
	}
	if (found.is_valid() && found == feed) {
		return true;
	}
	if (feed.is_valid()) {
		release_camera_feed(); // the feed followed is gone (an unplugged webcam)
	}
	if (found.is_null()) {
		const std::string absent = listed.empty() ? "CameraServer lists no camera feed (none plugged in, or, on Android, no CAMERA permission)"
												  : "not among CameraServer's feeds: " + drivers::comma_list(listed);
		if (absent != feed_absent) {
			feed_absent = absent;
			feed_frames->set_absent(absent);
		}
		return false;
	}
	feed = found;
	feed_frames->set_name(feed_label(feed->get_name().utf8_string()));
	feed->connect("frame_changed", Callable(this, "_camera_feed_frame"));
	if (!feed->is_active()) {
		feed->set_active(true);
		feed_activated = true;
	}
	feed_taken = feed_signals.load();
	return true;
}

std::shared_ptr<drivers::PushedFrames> RigCapture::start_camera_feed() {
	release_camera_feed();
	feed_frames = std::make_shared<drivers::PushedFrames>(
			fisheye_device.is_empty() ? std::string("Godot camera feed (the first listed)") : feed_label(fisheye_device.utf8_string()));
	poll_camera_feed();
	return feed_frames;
}

void RigCapture::poll_camera_feed() {
	if (!feed_frames || !follow_camera_feed()) {
		return;
	}
	const uint64_t signals = feed_signals.load();
	if (signals == feed_taken) {
		return; // no new frame since the last one read
	}
	feed_taken = signals;
	const uint64_t arrival_ns = feed_arrival_ns.load();
	std::string why;
	cv::Mat image = feed_reader.read(feed, &why);
	if (image.empty()) {
		if (why != feed_absent) {
			feed_absent = why;
			feed_frames->set_absent(why);
		}
		return;
	}
	feed_absent.clear();
	feed_frames->push(std::move(image), arrival_ns, int64_t(signals));
}

void RigCapture::release_camera_feed() {
	if (feed.is_valid()) {
		const Callable on_frame(this, "_camera_feed_frame");
		if (feed->is_connected("frame_changed", on_frame)) {
			feed->disconnect("frame_changed", on_frame);
		}
		if (feed_activated) {
			feed->set_active(false);
		}
	}
	feed.unref();
	feed_activated = false;
	feed_reader.reset();
	feed_absent.clear();
}

} // namespace roomprobe
