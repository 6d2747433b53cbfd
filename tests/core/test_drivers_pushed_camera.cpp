// A camera whose frames its host pushes (capture/pushed_camera.h: Godot's camera feeds, read by
// RigCapture on the main thread): through a DeviceCapture thread like any device, stamped when the
// host had the frame, the newest only, and an absent camera a state with the host's reason.

#include "capture/device_capture.h"
#include "capture/pushed_camera.h"

#include "test_waiting.h"

#include <doctest/doctest.h>

#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

using namespace roomprobe::drivers;
using roomprobe::test::contains;
using roomprobe::test::wait_until;

namespace {

cv::Mat frame_of(int p_value, int p_width = 64, int p_height = 48) {
	return cv::Mat(p_height, p_width, CV_8UC3, cv::Scalar(p_value, 255 - p_value, 7));
}

struct Received {
	std::mutex mutex;
	std::vector<CapturedFrame> frames;
	size_t count() {
		std::lock_guard lock(mutex);
		return frames.size();
	}
};

} // namespace

TEST_CASE("pushed camera: only the newest frame waits, and a take empties it") {
	PushedFrames frames("Godot camera feed 'test'");
	frames.push(frame_of(1), 100, 0);
	frames.push(frame_of(2), 200, 1);
	cv::Mat image;
	uint64_t arrival_ns = 0;
	int64_t id = -1;
	REQUIRE(frames.take(10, &image, &arrival_ns, &id));
	CHECK(image.at<cv::Vec3b>(0, 0)[0] == 2);
	CHECK(arrival_ns == 200);
	CHECK(id == 1);
	CHECK_FALSE(frames.take(10, &image, &arrival_ns, &id));
	CHECK(frames.pushed_count() == 2);
}

TEST_CASE("pushed camera: frames go through a capture thread stamped when the host had them, less the latency") {
	auto frames = std::make_shared<PushedFrames>("Godot camera feed 'test'");
	Received got;
	DeviceCaptureOptions options;
	options.latency_s = 0.010;
	DeviceCapture capture(make_pushed_fisheye_source(frames, 64, 48), options, [&](CapturedFrame &&p_frame) {
		std::lock_guard lock(got.mutex);
		got.frames.push_back(std::move(p_frame));
	});
	REQUIRE(capture.start().empty());
	// Each frame says it reached the host 300 ms before it was pushed (a slow main thread): the
	// stamp is that arrival, not the push and not the take.
	std::vector<double> arrivals_s;
	const auto received = [&](int64_t p_id) {
		std::lock_guard lock(got.mutex);
		return !got.frames.empty() && got.frames.back().fisheye.capture.device_frame_id == p_id;
	};
	for (int i = 0; i < 5; i++) {
		const uint64_t arrival_ns = monotonic_clock_ns() - 300'000'000;
		arrivals_s.push_back(double(arrival_ns) * 1e-9);
		// Pushed again until taken: a frame pushed before the thread opened the camera is dropped.
		REQUIRE(wait_until(10.0, [&] {
			frames->push(frame_of(10 * i), arrival_ns, i);
			std::this_thread::sleep_for(std::chrono::milliseconds(20));
			return received(i);
		}));
	}
	CHECK(capture.status().state == DeviceState::Streaming);
	capture.stop();
	std::lock_guard lock(got.mutex);
	for (const CapturedFrame &frame : got.frames) {
		const int64_t id = frame.fisheye.capture.device_frame_id;
		REQUIRE((id >= 0 && id < 5));
		CHECK_FALSE(frame.is_rgbd);
		CHECK(frame.fisheye.image.at<cv::Vec3b>(0, 0)[0] == 10 * id);
		// The only slack is the capture thread's own time between the take and its clock read.
		CHECK(frame.host_time_s >= arrivals_s[id] - options.latency_s - 1e-6);
		CHECK(frame.host_time_s <= arrivals_s[id] - options.latency_s + 0.050);
	}
}

TEST_CASE("pushed camera: an absent camera is one state with the host's reason; frames of the wrong size are refused naming both sizes") {
	auto frames = std::make_shared<PushedFrames>("Godot camera feed 'Rear'");
	DeviceCaptureOptions options;
	options.retry_first_s = 0.05;
	options.retry_max_s = 0.1;
	DeviceCapture capture(make_pushed_fisheye_source(frames, 64, 48), options, [](CapturedFrame &&) {});
	frames->set_absent("not among CameraServer's 2 feeds (Front, Depth)");
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(10.0, [&] { return capture.status().state == DeviceState::Disconnected; }));
	CHECK(contains(capture.status().reason, "Godot camera feed 'Rear'"));
	CHECK(contains(capture.status().reason, "not among CameraServer's 2 feeds (Front, Depth)"));
	// The feed appears: it streams.
	REQUIRE(wait_until(10.0, [&] {
		frames->push(frame_of(3), monotonic_clock_ns(), 0);
		return capture.status().state == DeviceState::Streaming;
	}));
	// A feed in another mode: disconnected, with what came and what the rig wants.
	REQUIRE(wait_until(10.0, [&] {
		frames->push(frame_of(3, 640, 480), monotonic_clock_ns(), 1);
		return capture.status().state == DeviceState::Disconnected;
	}));
	CHECK(contains(capture.status().reason, "fisheye frames are 640x480, the rig file says 64x48"));
	capture.stop();
}
