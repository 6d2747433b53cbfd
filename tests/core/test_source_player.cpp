// The frame source layer (source/recording_player.h, source/paced_player.h): a small recording
// written here plays back in time order, limited as asked, stepped, taken up to a time, and paced
// on a clock that drops all but the newest frame of each stream when the reader falls behind.

#include "source/paced_player.h"
#include "source/recording_player.h"
#include "recording/recording_writer.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

constexpr int RGBD_FRAMES = 10; // at 0.1 s apart from t = 5 s
constexpr int FISHEYE_FRAMES = 5; // at 0.2 s apart, 0.05 s after an RGB-D frame
constexpr double FIRST_S = 5.0;

// The recording, written once per process.
const std::string &recording() {
	static const std::string folder = [] {
		const fs::path path = fs::temp_directory_path() / ("roomprobe_player_" + std::to_string(::getpid()));
		fs::remove_all(path);
		RecordingWriter writer;
		const Rig rig = small_test_rig(32, 24, 40, 40);
		REQUIRE(writer.open_without_room(path.string(), rig).ok);
		for (int i = 0; i < RGBD_FRAMES; i++) {
			RgbdFrame frame;
			frame.timestamp_s = frame.depth_timestamp_s = FIRST_S + 0.1 * i;
			frame.rgb = cv::Mat(24, 32, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i));
			frame.depth_m = cv::Mat(24, 32, CV_32FC1, cv::Scalar(1.0f + 0.01f * float(i)));
			REQUIRE(writer.add_rgbd(frame).ok);
			if (i % 2 == 0) {
				FisheyeFrame fisheye;
				fisheye.timestamp_s = FIRST_S + 0.1 * i + 0.05 - rig.fisheye_time_offset_s;
				fisheye.image = cv::Mat(40, 40, CV_8UC3, cv::Scalar(10 * i, 0, 0));
				REQUIRE(writer.add_fisheye(fisheye).ok);
			}
		}
		REQUIRE(writer.close().ok);
		return path.string();
	}();
	return folder;
}

RecordingPlayer open(const PlayerOptions &p_options = PlayerOptions()) {
	RecordingPlayer player;
	const std::string error = open_player(recording(), p_options, &player);
	REQUIRE_MESSAGE(error.empty(), error);
	return player;
}

} // namespace

TEST_CASE("frame source: a recording plays in time order, every frame read as written, and stops at its end") {
	RecordingPlayer player = open();
	REQUIRE(player.events().size() == size_t(RGBD_FRAMES + FISHEYE_FRAMES));
	CHECK(player.start_s() == doctest::Approx(FIRST_S));
	double last_s = -1.0;
	int rgbd = 0, fisheye = 0;
	while (!player.at_end()) {
		const SourceFrame frame = player.next();
		REQUIRE_MESSAGE(frame.ok, frame.error);
		CHECK(frame.event.time_s >= last_s);
		last_s = frame.event.time_s;
		if (frame.event.stream == RecordingStream::Rgbd) {
			CHECK(frame.rgbd.rgb.at<cv::Vec3b>(0, 0)[1] == uint8_t(2 * rgbd)); // the frame of that index
			CHECK(frame.rgbd.timestamp_s == doctest::Approx(FIRST_S + 0.1 * rgbd));
			rgbd++;
		} else {
			CHECK(frame.fisheye.image.at<cv::Vec3b>(0, 0)[0] == uint8_t(20 * fisheye));
			fisheye++;
		}
	}
	CHECK(rgbd == RGBD_FRAMES);
	CHECK(fisheye == FISHEYE_FRAMES);
	const SourceFrame end = player.next();
	CHECK_FALSE(end.ok);
	CHECK(end.error == "end");
}

TEST_CASE("frame source: the limits cut the recording where asked, and a stream left out is never read") {
	PlayerOptions first_four;
	first_four.max_rgbd_frames = 4;
	const RecordingPlayer four = open(first_four);
	CHECK(four.rgbd_events() == 4);
	// Up to (not including) the fifth RGB-D frame: the fisheye frames at 0.05 and 0.25 s.
	CHECK(four.events().size() == 6);
	CHECK(four.events().back().time_s < FIRST_S + 0.4 - 1e-9);

	PlayerOptions half_second;
	half_second.max_seconds = 0.5;
	const RecordingPlayer half = open(half_second);
	for (const PlaybackEvent &event : half.events()) {
		CHECK(event.time_s - FIRST_S <= 0.5 + 1e-9);
	}
	CHECK(half.rgbd_events() == 6);

	PlayerOptions rgbd_only;
	rgbd_only.fisheye = false;
	const RecordingPlayer depth = open(rgbd_only);
	CHECK(depth.events().size() == size_t(RGBD_FRAMES));
}

TEST_CASE("frame source: take_until hands out each event once, up to the time; KeepNewest keeps the newest of each stream and counts the rest") {
	RecordingPlayer player = open();
	const std::vector<size_t> first = player.take_until(FIRST_S + 0.25);
	CHECK(first.size() == 5); // RGB-D at 0, 0.1, 0.2 and fisheye at 0.05, 0.25
	CHECK(player.take_until(FIRST_S + 0.25).empty());

	RecordingPlayer paced = open();
	size_t dropped = 0;
	const std::vector<size_t> due = paced.take_due(0.55, DropPolicy::KeepNewest, &dropped);
	REQUIRE(due.size() == 2);
	CHECK(paced.events()[due[0]].time_s == doctest::Approx(FIRST_S + 0.45)); // fisheye at 0.45
	CHECK(paced.events()[due[1]].time_s == doctest::Approx(FIRST_S + 0.5)); // RGB-D at 0.5
	CHECK(dropped == 5 + 2); // RGB-D 0..0.4, fisheye 0.05 and 0.25
}

TEST_CASE("frame source: a paced player on a clock its owner advances sinks the due frames in order and drops what a slow clock skipped") {
	PacedPlayer paced(open());
	std::mutex mutex;
	std::vector<PlaybackEvent> sunk;
	PacedOptions options;
	options.clock = PaceClock::Manual;
	paced.start(options, [&](SourceFrame &&p_frame) {
		CHECK(p_frame.ok);
		const std::lock_guard<std::mutex> lock(mutex);
		sunk.push_back(p_frame.event);
	});
	const auto wait_for = [&](size_t p_count) {
		for (int i = 0; i < 400; i++) {
			{
				const std::lock_guard<std::mutex> lock(mutex);
				if (sunk.size() >= p_count) {
					return;
				}
			}
			std::this_thread::sleep_for(std::chrono::milliseconds(5));
		}
	};
	wait_for(1); // the first frame is due at clock 0
	CHECK(paced.step().error == "running"); // one reader at a time
	paced.advance(0.55); // everything to 0.5 s is due at once: the newest of each stream is read
	wait_for(3);
	paced.advance(10.0);
	for (int i = 0; i < 400 && !paced.reached_end(); i++) {
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
	paced.stop();
	CHECK(paced.reached_end());
	const std::lock_guard<std::mutex> lock(mutex);
	REQUIRE(sunk.size() == 5); // 0 s; 0.45 and 0.5; 0.85 and 0.9
	for (size_t i = 1; i < sunk.size(); i++) {
		CHECK(sunk[i].time_s >= sunk[i - 1].time_s);
	}
	CHECK(paced.dropped() == size_t(RGBD_FRAMES + FISHEYE_FRAMES) - 5);
}

TEST_CASE("frame source: on the wall clock with no drops every frame is sunk, no earlier than its time; step() reads one at a time") {
	PacedPlayer paced(open());
	std::vector<double> sunk_at_s;
	std::vector<double> due_s;
	const auto start = std::chrono::steady_clock::now();
	PacedOptions options;
	options.clock = PaceClock::Wall;
	options.speed = 4.0; // 0.95 s of recording in about 0.24 s
	options.drop = DropPolicy::None;
	std::atomic<bool> ended{ false };
	options.on_end = [&] { ended = true; };
	paced.start(options, [&](SourceFrame &&p_frame) {
		sunk_at_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
		due_s.push_back((p_frame.event.time_s - FIRST_S) / 4.0);
	});
	for (int i = 0; i < 400 && !ended; i++) {
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
	paced.stop();
	CHECK(ended);
	REQUIRE(sunk_at_s.size() == size_t(RGBD_FRAMES + FISHEYE_FRAMES));
	for (size_t i = 0; i < sunk_at_s.size(); i++) {
		CHECK(sunk_at_s[i] >= due_s[i] - 1e-3); // never early
	}
	CHECK(paced.dropped() == 0);

	// Stopped part way on the wall clock, it goes on from where it stood.
	paced.rewind();
	sunk_at_s.clear();
	due_s.clear();
	ended = false;
	const auto restart = std::chrono::steady_clock::now();
	paced.start(options, [&](SourceFrame &&p_frame) {
		sunk_at_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - restart).count());
		due_s.push_back((p_frame.event.time_s - FIRST_S) / 4.0);
	});
	std::this_thread::sleep_for(std::chrono::milliseconds(100));
	paced.stop();
	const double stopped_at_s = paced.clock_s();
	CHECK(stopped_at_s > 0.0);
	const size_t before = sunk_at_s.size();
	paced.start(options, [&](SourceFrame &&p_frame) { sunk_at_s.push_back(p_frame.event.time_s - FIRST_S); });
	CHECK(paced.clock_s() >= stopped_at_s); // the clock goes on, not from 0
	for (int i = 0; i < 400 && !ended; i++) {
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
	paced.stop();
	CHECK(ended);
	CHECK(sunk_at_s.size() == size_t(RGBD_FRAMES + FISHEYE_FRAMES)); // every frame once, across the pause
	CHECK(sunk_at_s.size() > before);

	paced.rewind();
	const SourceFrame first = paced.step();
	CHECK(first.ok);
	CHECK(first.event.time_s == doctest::Approx(FIRST_S));
	CHECK(paced.step().event.time_s == doctest::Approx(FIRST_S + 0.05));
}
