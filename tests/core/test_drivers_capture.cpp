// Live capture (extension/drivers/capture): the capture thread's states, reconnection and one
// clock, against a scripted source and against the real SDK stacks without hardware: Aravis'
// Fake camera, its GigE Vision simulator killed and started again, and OpenCV's VideoCapture
// reading a video file as the UVC fisheye. GenICam's Bayer names against a mosaic made here.

#include "capture/capture_sources.h"
#include "capture/device_capture.h"
#include "capture/pixel_formats.h"
#include "gv_simulator.h"

#include "test_waiting.h"

#include <doctest/doctest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

using namespace roomprobe::drivers;
using roomprobe::test::contains;
using roomprobe::test::wait_until;

namespace {

// Everything a capture delivered, for the test thread to read.
struct Collected {
	std::mutex mutex;
	std::vector<CapturedFrame> frames;
	std::vector<DeviceStatus> changes;

	DeviceCapture::FrameSink frame_sink() {
		return [this](CapturedFrame &&p_frame) {
			std::lock_guard lock(mutex);
			frames.push_back(std::move(p_frame));
		};
	}
	DeviceCapture::StateSink state_sink() {
		return [this](const DeviceStatus &p_status) {
			std::lock_guard lock(mutex);
			changes.push_back(p_status);
		};
	}
	size_t frame_count() {
		std::lock_guard lock(mutex);
		return frames.size();
	}
	std::vector<DeviceState> states() {
		std::lock_guard lock(mutex);
		std::vector<DeviceState> result;
		for (const DeviceStatus &status : changes) {
			if (result.empty() || result.back() != status.state) {
				result.push_back(status.state);
			}
		}
		return result;
	}
};

// A device driven by a script: each open() and grab() takes the next step of its list (the last
// one repeats). A frame's device time counts up.
class ScriptedSource : public CaptureSource {
public:
	enum Step { OPEN_FAILS, OPEN_OK, FRAME, TIMEOUT, LOST };

	explicit ScriptedSource(std::vector<Step> p_opens, std::vector<Step> p_grabs) :
			opens(std::move(p_opens)), grabs(std::move(p_grabs)) {}

	std::string name() const override { return "scripted device"; }
	DriverStatus open() override {
		open_calls++;
		if (next(opens) != OPEN_OK) {
			return { "scripted device: not plugged in" };
		}
		if (frames_after_reopen && ++successful_opens > 1) {
			grabs = { FRAME };
		}
		return {};
	}
	GrabOutcome grab(int p_timeout_ms) override {
		GrabOutcome outcome;
		switch (next(grabs)) {
			case FRAME:
				outcome.kind = GrabOutcome::Frame;
				outcome.frame.is_rgbd = false;
				outcome.frame.fisheye.image = cv::Mat(4, 4, CV_8UC1, cv::Scalar(7));
				outcome.frame.fisheye.capture.device_time_s = double(++frames) / 30.0;
				outcome.frame.processing_s = processing_s;
				std::this_thread::sleep_for(std::chrono::milliseconds(2));
				break;
			case TIMEOUT:
				outcome.kind = GrabOutcome::Timeout;
				std::this_thread::sleep_for(std::chrono::milliseconds(p_timeout_ms));
				break;
			default:
				outcome.kind = GrabOutcome::Lost;
				outcome.error = "scripted device: unplugged";
				break;
		}
		return outcome;
	}
	void close() override { close_calls++; }

	std::atomic<int> open_calls{ 0 };
	std::atomic<int> close_calls{ 0 };
	bool frames_after_reopen = false; // a reopened device streams at once (the rest of the script is dropped)
	double processing_s = 0.0; // what each frame says its conversion took

private:
	Step next(std::vector<Step> &p_steps) {
		const Step step = p_steps.front();
		if (p_steps.size() > 1) {
			p_steps.erase(p_steps.begin());
		}
		return step;
	}

	std::vector<Step> opens;
	std::vector<Step> grabs;
	int frames = 0;
	int successful_opens = 0;
};

// GenICam names the 2x2 block row by row: the mosaic of p_image under that name.
CameraFrame mosaic(const cv::Mat &p_rgb, const std::string &p_format) {
	const std::string order = p_format.substr(5, 2); // "RG", "BG", "GR", "GB"
	// The colours of the four cells (0,0) (0,1) (1,0) (1,1).
	int cells[4];
	if (order == "RG") {
		cells[0] = 0, cells[1] = 1, cells[2] = 1, cells[3] = 2;
	} else if (order == "BG") {
		cells[0] = 2, cells[1] = 1, cells[2] = 1, cells[3] = 0;
	} else if (order == "GR") {
		cells[0] = 1, cells[1] = 0, cells[2] = 2, cells[3] = 1;
	} else {
		cells[0] = 1, cells[1] = 2, cells[2] = 0, cells[3] = 1;
	}
	CameraFrame frame;
	frame.width = p_rgb.cols;
	frame.height = p_rgb.rows;
	frame.channels = 1;
	frame.pixel_format = p_format;
	frame.pixels.resize(size_t(p_rgb.cols) * size_t(p_rgb.rows));
	for (int y = 0; y < p_rgb.rows; y++) {
		for (int x = 0; x < p_rgb.cols; x++) {
			frame.pixels[size_t(y) * size_t(p_rgb.cols) + size_t(x)] = p_rgb.at<cv::Vec3b>(y, x)[cells[(y % 2) * 2 + (x % 2)]];
		}
	}
	return frame;
}

std::filesystem::path fresh_folder(const std::string &p_name) {
	const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("roomprobe_capture_" + p_name + "_" + std::to_string(::getpid()));
	std::filesystem::remove_all(folder);
	std::filesystem::create_directories(folder);
	return folder;
}

std::atomic<uint64_t> stepping_clock_ns{ 0 };
// A clock that runs, then steps back 10 s once (as a wall clock set by NTP would).
uint64_t clock_that_steps_back() {
	const uint64_t now = monotonic_clock_ns() + 100'000'000'000ull;
	return now - (stepping_clock_ns.load() > 0 && now > stepping_clock_ns.load() ? 10'000'000'000ull : 0);
}

} // namespace

TEST_CASE("capture: GenICam's Bayer names demosaic to the colours they were made from; RGB8, BGR8 and Mono8 keep theirs") {
	const cv::Vec3b colour(200, 90, 30); // R, G, B
	cv::Mat rgb(16, 20, CV_8UC3, cv::Scalar(colour[0], colour[1], colour[2]));
	for (const char *format : { "BayerRG8", "BayerBG8", "BayerGR8", "BayerGB8" }) {
		CAPTURE(format);
		std::string error;
		const cv::Mat image = camera_frame_to_image(mosaic(rgb, format), &error);
		REQUIRE_MESSAGE(!image.empty(), error);
		REQUIRE(image.type() == CV_8UC3);
		// A flat colour demosaics exactly away from the border.
		const cv::Vec3b inside = image.at<cv::Vec3b>(8, 10);
		CHECK(inside == colour);
	}

	CameraFrame packed;
	packed.width = 2;
	packed.height = 1;
	packed.channels = 3;
	packed.pixels = { 10, 20, 30, 40, 50, 60 };
	packed.pixel_format = "RGB8";
	std::string error;
	cv::Mat image = camera_frame_to_image(packed, &error);
	REQUIRE_MESSAGE(!image.empty(), error);
	CHECK(image.at<cv::Vec3b>(0, 1) == cv::Vec3b(40, 50, 60));
	packed.pixel_format = "BGR8";
	image = camera_frame_to_image(packed, &error);
	REQUIRE_MESSAGE(!image.empty(), error);
	CHECK(image.at<cv::Vec3b>(0, 1) == cv::Vec3b(60, 50, 40));

	packed.pixel_format = "Mono8"; // 6 bytes in 3 channels is not a 2x1 Mono8 image
	CHECK(camera_frame_to_image(packed, &error).empty());
	CHECK(contains(error, "Mono8"));
	packed.pixel_format = "Mono12";
	CHECK(camera_frame_to_image(packed, &error).empty());
	CHECK(contains(error, "not supported"));
}

TEST_CASE("capture: a device that is absent, then appears, then is unplugged goes disconnected, streaming, disconnected, streaming") {
	auto source = std::make_unique<ScriptedSource>(
			std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_FAILS, ScriptedSource::OPEN_FAILS, ScriptedSource::OPEN_OK },
			std::vector<ScriptedSource::Step>{ ScriptedSource::FRAME, ScriptedSource::FRAME, ScriptedSource::FRAME, ScriptedSource::LOST, ScriptedSource::FRAME });
	ScriptedSource *script = source.get();
	Collected got;
	DeviceCaptureOptions options;
	options.retry_first_s = 0.02;
	options.retry_max_s = 0.05;
	DeviceCapture capture(std::move(source), options, got.frame_sink(), got.state_sink());
	CHECK(capture.status().state == DeviceState::Stopped);
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(10.0, [&] { return got.frame_count() >= 10; }));
	capture.stop();

	const std::vector<DeviceState> states = got.states();
	const std::vector<DeviceState> expected = { DeviceState::Connecting, DeviceState::Disconnected, DeviceState::Connecting,
		DeviceState::Disconnected, DeviceState::Connecting, DeviceState::Streaming, DeviceState::Disconnected,
		DeviceState::Connecting, DeviceState::Streaming };
	CHECK(states == expected);
	const DeviceStatus status = capture.status();
	CHECK(status.state == DeviceState::Stopped);
	CHECK(status.reconnections == 1);
	CHECK(status.frames == got.frame_count());
	CHECK(script->open_calls.load() == 4); // two failures, the first stream, the reconnection
	CHECK(script->close_calls.load() >= 2);
	{
		std::lock_guard lock(got.mutex);
		bool named = false;
		for (const DeviceStatus &change : got.changes) {
			if (change.state == DeviceState::Disconnected) {
				CHECK(contains(change.reason, "scripted device"));
				CHECK(contains(change.reason, "trying again in"));
				named = true;
			}
		}
		CHECK(named);
	}
}

TEST_CASE("capture: no frame for a while is stalled, then a reopen; frames resume streaming") {
	std::vector<ScriptedSource::Step> grabs = { ScriptedSource::FRAME };
	grabs.push_back(ScriptedSource::TIMEOUT); // silent until reopened
	auto source = std::make_unique<ScriptedSource>(std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_OK }, grabs);
	ScriptedSource *script = source.get();
	script->frames_after_reopen = true;
	Collected got;
	DeviceCaptureOptions options;
	options.grab_timeout_ms = 10;
	options.stall_after_s = 0.05;
	options.reopen_after_s = 0.12;
	options.retry_first_s = 0.01;
	DeviceCapture capture(std::move(source), options, got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(10.0, [&] { return got.frame_count() >= 5; }));
	capture.stop();
	const std::vector<DeviceState> states = got.states();
	REQUIRE(states.size() >= 6);
	CHECK(states[1] == DeviceState::Streaming);
	CHECK(states[2] == DeviceState::Stalled);
	CHECK(states[3] == DeviceState::Disconnected); // silent past reopen_after_s: closed and opened again
	CHECK(states[5] == DeviceState::Streaming);
	CHECK(script->open_calls.load() == 2);
	CHECK(capture.status().reconnections == 1);
}

TEST_CASE("capture: frames are stamped on one monotonic clock less the latency, in order even when the clock steps back") {
	SUBCASE("the host's monotonic clock") {
		auto source = std::make_unique<ScriptedSource>(std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_OK },
				std::vector<ScriptedSource::Step>{ ScriptedSource::FRAME });
		Collected got;
		DeviceCaptureOptions options;
		options.latency_s = 0.025;
		DeviceCapture capture(std::move(source), options, got.frame_sink());
		const double before_s = double(monotonic_clock_ns()) * 1e-9;
		REQUIRE(capture.start().empty());
		REQUIRE(wait_until(10.0, [&] { return got.frame_count() >= 20; }));
		capture.stop();
		const double after_s = double(monotonic_clock_ns()) * 1e-9;
		std::lock_guard lock(got.mutex);
		double last = -1e300;
		for (const CapturedFrame &frame : got.frames) {
			CHECK(frame.host_time_s > last);
			CHECK(frame.host_time_s >= before_s - options.latency_s);
			CHECK(frame.host_time_s <= after_s - options.latency_s);
			CHECK(frame.fisheye.timestamp_s == frame.host_time_s);
			last = frame.host_time_s;
		}
	}
	SUBCASE("a source's conversion time is taken off the stamp: the frame arrived before it was converted") {
		auto source = std::make_unique<ScriptedSource>(std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_OK },
				std::vector<ScriptedSource::Step>{ ScriptedSource::FRAME });
		source->processing_s = 0.040;
		std::mutex mutex;
		std::vector<std::pair<double, double>> stamped_received; // host_time_s, when the sink had it
		DeviceCapture capture(std::move(source), DeviceCaptureOptions(), [&](CapturedFrame &&p_frame) {
			const double received_s = double(monotonic_clock_ns()) * 1e-9;
			std::lock_guard lock(mutex);
			stamped_received.emplace_back(p_frame.host_time_s, received_s);
		});
		REQUIRE(capture.start().empty());
		REQUIRE(wait_until(10.0, [&] { std::lock_guard lock(mutex); return stamped_received.size() >= 10; }));
		capture.stop();
		std::lock_guard lock(mutex);
		for (size_t i = 0; i < stamped_received.size(); i++) {
			CHECK(stamped_received[i].first <= stamped_received[i].second - 0.040);
			if (i > 0) {
				CHECK(stamped_received[i].first > stamped_received[i - 1].first);
			}
		}
	}
	SUBCASE("a clock that steps back 10 s mid-capture") {
		auto source = std::make_unique<ScriptedSource>(std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_OK },
				std::vector<ScriptedSource::Step>{ ScriptedSource::FRAME });
		Collected got;
		DeviceCaptureOptions options;
		options.clock = clock_that_steps_back;
		stepping_clock_ns = 0;
		DeviceCapture capture(std::move(source), options, got.frame_sink());
		REQUIRE(capture.start().empty());
		REQUIRE(wait_until(10.0, [&] { return got.frame_count() >= 10; }));
		stepping_clock_ns = clock_that_steps_back(); // from now on it reads 10 s earlier
		const size_t at_step = got.frame_count();
		REQUIRE(wait_until(10.0, [&] { return got.frame_count() >= at_step + 10; }));
		capture.stop();
		std::lock_guard lock(got.mutex);
		for (size_t i = 1; i < got.frames.size(); i++) {
			CHECK(got.frames[i].host_time_s > got.frames[i - 1].host_time_s);
			CHECK(got.frames[i].capture().device_time_s > got.frames[i - 1].capture().device_time_s);
		}
	}
}

TEST_CASE("capture: bad options are refused naming the option") {
	DeviceCaptureOptions options;
	options.latency_s = std::nan("");
	DeviceCapture capture(std::make_unique<ScriptedSource>(std::vector<ScriptedSource::Step>{ ScriptedSource::OPEN_OK },
								  std::vector<ScriptedSource::Step>{ ScriptedSource::FRAME }),
			options, nullptr);
	const std::string error = capture.start();
	CHECK(contains(error, "latency_s"));
	CHECK(contains(error, "scripted device"));
	CHECK_FALSE(capture.is_running());
}

TEST_CASE("capture: Aravis' Fake camera streams as the fisheye through its own thread, with exposure and gain on every frame") {
	FisheyeSourceSettings settings;
	settings.device = "Fake_1";
	settings.auto_exposure = false;
	settings.exposure_us = 5000.0;
	settings.gain = 2.0;
	Collected got;
	DeviceCapture capture(make_aravis_fisheye_source(settings), DeviceCaptureOptions(), got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	const bool streamed = wait_until(20.0, [&] { return got.frame_count() >= 5; });
	const DeviceStatus status = capture.status();
	capture.stop();
	REQUIRE_MESSAGE(streamed, status.reason);
	std::lock_guard lock(got.mutex);
	for (const CapturedFrame &frame : got.frames) {
		CHECK_FALSE(frame.is_rgbd);
		CHECK(frame.fisheye.image.type() == CV_8UC1); // the Fake camera's Mono8
		CHECK(frame.fisheye.image.cols > 0);
		CHECK(frame.fisheye.capture.exposure_us == doctest::Approx(5000.0));
		CHECK(frame.fisheye.capture.gain == doctest::Approx(2.0));
	}
	CHECK(got.frames.back().capture().device_frame_id > got.frames.front().capture().device_frame_id);
}

TEST_CASE("capture: the fisheye's size is checked against the rig's") {
	FisheyeSourceSettings settings;
	settings.device = "Fake_1";
	settings.width = 1024;
	settings.height = 1024;
	Collected got;
	DeviceCaptureOptions options;
	options.retry_first_s = 5.0;
	options.retry_max_s = 5.0;
	DeviceCapture capture(make_aravis_fisheye_source(settings), options, got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(20.0, [&] { return capture.status().state == DeviceState::Disconnected; }));
	const DeviceStatus status = capture.status();
	capture.stop();
	CHECK(got.frame_count() == 0);
	CHECK(contains(status.reason, "the rig file says 1024x1024"));
	CHECK(contains(status.reason, "Fake_1"));
}

TEST_CASE("capture: a GigE camera killed mid-stream is disconnected, and streams again by itself when it is back (needs arv-fake-gv-camera-0.8)" *
		doctest::skip(gv_simulator_missing("the reconnection test")) * doctest::timeout(90)) {
	auto simulator = std::make_unique<GvSimulator>();
	REQUIRE(simulator->running());
	FisheyeSourceSettings settings;
	settings.device = "127.0.0.1";
	Collected got;
	DeviceCaptureOptions options;
	options.stall_after_s = 0.5;
	options.reopen_after_s = 2.0;
	options.retry_first_s = 0.2;
	options.retry_max_s = 1.0;
	DeviceCapture capture(make_aravis_fisheye_source(settings), options, got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	REQUIRE_MESSAGE(wait_until(20.0, [&] { return got.frame_count() >= 3; }), capture.status().reason);
	REQUIRE_MESSAGE(simulator->running(), "another GigE Vision simulator already serves 127.0.0.1; ours could not start");

	simulator->kill(); // as good as pulling the cable
	CHECK_MESSAGE(wait_until(30.0, [&] { return capture.status().state == DeviceState::Disconnected; }), capture.status().reason);
	MESSAGE(("after the kill: " + capture.status().reason));
	const size_t frames_while_down = got.frame_count();

	simulator = std::make_unique<GvSimulator>(); // plugged in again
	REQUIRE(simulator->running());
	CHECK_MESSAGE(wait_until(40.0, [&] { return capture.status().state == DeviceState::Streaming && got.frame_count() > frames_while_down + 2; }),
			capture.status().reason);
	const DeviceStatus status = capture.status();
	capture.stop();
	CHECK(status.reconnections >= 1);
	const std::vector<DeviceState> states = got.states();
	CHECK(std::find(states.begin(), states.end(), DeviceState::Disconnected) != states.end());
}

TEST_CASE("capture: a UVC fisheye through OpenCV's VideoCapture (a video file in place of /dev/video: no v4l2loopback here)") {
	const std::filesystem::path folder = fresh_folder("uvc");
	const std::string video = (folder / "fisheye.avi").string();
	const int frames_written = 12;
	{
		cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, cv::Size(64, 48));
		REQUIRE(writer.isOpened());
		for (int i = 0; i < frames_written; i++) {
			// B, G, R for the writer: a red image whose brightness counts the frames.
			writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(0, 0, 100 + 10 * i)));
		}
	}
	FisheyeSourceSettings settings;
	settings.device = video;
	settings.width = 64;
	settings.height = 48;
	Collected got;
	DeviceCaptureOptions options;
	options.stall_after_s = 0.3;
	options.reopen_after_s = 60.0;
	DeviceCapture capture(make_uvc_fisheye_source(settings), options, got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	REQUIRE_MESSAGE(wait_until(20.0, [&] { return capture.status().state == DeviceState::Stalled; }), capture.status().reason);
	capture.stop();
	std::lock_guard lock(got.mutex);
	REQUIRE(got.frames.size() == size_t(frames_written));
	for (size_t i = 0; i < got.frames.size(); i++) {
		const cv::Mat &image = got.frames[i].fisheye.image;
		REQUIRE(image.type() == CV_8UC3);
		const cv::Vec3b centre = image.at<cv::Vec3b>(24, 32);
		CHECK(std::abs(int(centre[0]) - (100 + 10 * int(i))) <= 4); // red first: R, G, B
		CHECK(centre[2] <= 4);
	}
	// Played at the file's 30 Hz, as a camera would send it: not faster over the whole file (a
	// busy machine may deliver one frame late and the next one early, so single gaps vary).
	const double span_s = got.frames.back().host_time_s - got.frames.front().host_time_s;
	CHECK(span_s > 0.9 * double(got.frames.size() - 1) / 30.0);
	std::filesystem::remove_all(folder);
}

TEST_CASE("capture: an absent UVC camera or file is one clear state, not an error per grab") {
	FisheyeSourceSettings settings;
	settings.device = "/nonexistent/fisheye.avi";
	Collected got;
	DeviceCaptureOptions options;
	options.retry_first_s = 0.05;
	options.retry_max_s = 0.1;
	DeviceCapture capture(make_uvc_fisheye_source(settings), options, got.frame_sink(), got.state_sink());
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(10.0, [&] { return capture.status().changes >= 6; }));
	const DeviceStatus status = capture.status();
	capture.stop();
	CHECK(contains(status.reason, "/nonexistent/fisheye.avi"));
	CHECK(got.frame_count() == 0);
	const std::vector<DeviceState> states = got.states();
	for (DeviceState state : states) {
		CHECK((state == DeviceState::Connecting || state == DeviceState::Disconnected));
	}
}

TEST_CASE("capture: the Fake camera's Bayer and RGB8 formats arrive as R, G, B images; a 16-bit format is refused naming it") {
	for (const char *format : { "BayerRG8", "RGB8" }) {
		CAPTURE(format);
		FisheyeSourceSettings settings;
		settings.device = "Fake_1";
		settings.pixel_format = format;
		Collected got;
		DeviceCapture capture(make_aravis_fisheye_source(settings), DeviceCaptureOptions(), got.frame_sink());
		REQUIRE(capture.start().empty());
		const bool streamed = wait_until(20.0, [&] { return got.frame_count() >= 2; });
		const DeviceStatus status = capture.status();
		capture.stop();
		REQUIRE_MESSAGE(streamed, status.reason);
		std::lock_guard lock(got.mutex);
		CHECK(got.frames.front().fisheye.image.type() == CV_8UC3);
	}
	FisheyeSourceSettings settings;
	settings.device = "Fake_1";
	settings.pixel_format = "Mono16";
	DeviceCaptureOptions options;
	options.retry_first_s = 5.0;
	options.retry_max_s = 5.0;
	DeviceCapture capture(make_aravis_fisheye_source(settings), options, nullptr);
	REQUIRE(capture.start().empty());
	REQUIRE(wait_until(20.0, [&] { return capture.status().state == DeviceState::Disconnected; }));
	const DeviceStatus status = capture.status();
	capture.stop();
	CHECK(contains(status.reason, "Mono16"));
	CHECK(contains(status.reason, "not supported"));
}
