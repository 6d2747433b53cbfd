// LiveRig (capture/live_rig.h) on the real SDK stacks without hardware: the RGB-D camera through
// OpenNI2 (an .oni written here, played as if live) and the fisheye through Aravis' Fake camera,
// recorded live for 5 s and played back frame for frame (issue #12's round trip).

#include "capture/live_rig.h"
#include "recording/recording_reader.h"
#include "synth_test_rig.h"
#include "test_images.h"

#include <recording/oni_writer.h>

#include <doctest/doctest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

// 5 s of 64x48 RGB-D at 30 Hz. Frame f (device frame id f + 1), pixel i: depth (800 + 7 f + i)
// mm, colour (f, i % 256, 255 - f % 256): each frame tells which it is.
struct ScriptedOni {
	static constexpr int WIDTH = 64;
	static constexpr int HEIGHT = 48;
	static constexpr int FRAMES = 150;
	static constexpr uint64_t PERIOD_US = 33333;

	static uint16_t depth_mm(int p_frame, int p_pixel) { return uint16_t(800 + 7 * p_frame + p_pixel); }
	static cv::Vec3b colour(int p_frame, int p_pixel) { return cv::Vec3b(uchar(p_frame), uchar(p_pixel % 256), uchar(255 - p_frame % 256)); }

	static void write(const fs::path &p_path) {
		OniWriter writer;
		writer.add_stream(OniWriter::DEPTH, WIDTH, HEIGHT, 100, FRAMES); // 100: 1 mm depth
		writer.add_stream(OniWriter::COLOR, WIDTH, HEIGHT, 200, FRAMES); // 200: RGB888
		writer.begin_data();
		for (int f = 0; f < FRAMES; f++) {
			std::vector<uint16_t> depth(WIDTH * HEIGHT);
			std::vector<uint8_t> rgb(WIDTH * HEIGHT * 3);
			for (int i = 0; i < WIDTH * HEIGHT; i++) {
				depth[i] = depth_mm(f, i);
				const cv::Vec3b c = colour(f, i);
				for (int k = 0; k < 3; k++) {
					rgb[i * 3 + k] = c[k];
				}
			}
			const uint64_t timestamp_us = 1000 + uint64_t(f) * PERIOD_US;
			writer.add_frame(OniWriter::DEPTH, timestamp_us, uint32_t(f + 1), OniWriter::raw(depth));
			writer.add_frame(OniWriter::COLOR, timestamp_us, uint32_t(f + 1), OniWriter::raw(rgb));
		}
		REQUIRE(writer.save(p_path.string()).empty());
	}

	// Whether p_frame is the file's frame p_index, pixel for pixel.
	static bool is_frame(const RgbdFrame &p_frame, int p_index) {
		if (p_frame.rgb.cols != WIDTH || p_frame.rgb.rows != HEIGHT || p_frame.depth_m.size() != p_frame.rgb.size()) {
			return false;
		}
		for (int i = 0; i < WIDTH * HEIGHT; i++) {
			const int x = i % WIDTH;
			const int y = i / WIDTH;
			// The sources give RGB in R, G, B order (recording_types.h).
			if (p_frame.rgb.at<cv::Vec3b>(y, x) != colour(p_index, i)
					|| std::abs(p_frame.depth_m.at<float>(y, x) - depth_mm(p_index, i) * 0.001f) > 1e-6f) {
				return false;
			}
		}
		return true;
	}
};

} // namespace

TEST_CASE("live rig: 5 s recorded from OpenNI2 (an .oni) and Aravis' Fake camera play back frame for frame, with the same timestamps, images and device data") {
	const std::string tag = std::to_string(::getpid());
	const fs::path oni = fs::temp_directory_path() / ("roomprobe_live_rig_" + tag + ".oni");
	const fs::path folder = fs::temp_directory_path() / ("roomprobe_live_rig_" + tag);
	fs::remove_all(folder);
	ScriptedOni::write(oni);

	drivers::LiveRigSettings settings;
	settings.rgbd.uri = oni.string();
	settings.fisheye.device = "Fake_1";
	settings.fisheye.auto_exposure = false;
	settings.fisheye.exposure_us = 5000.0;
	settings.fisheye.gain = 1.0;
	const Rig rig = small_test_rig(ScriptedOni::WIDTH, ScriptedOni::HEIGHT, 512, 512); // the Fake camera's size

	// Everything the capture threads deliver, by stream and timestamp.
	std::mutex mutex;
	std::map<double, RgbdFrame> rgbd_sent;
	std::map<double, FisheyeFrame> fisheye_sent;
	drivers::LiveRig live;
	const std::string error = live.start(rig, settings, [&](drivers::CapturedFrame &&p_frame) {
		std::lock_guard lock(mutex);
		if (p_frame.is_rgbd) {
			rgbd_sent[p_frame.rgbd.timestamp_s] = std::move(p_frame.rgbd);
		} else {
			fisheye_sent[p_frame.fisheye.timestamp_s] = std::move(p_frame.fisheye);
		}
	});
	REQUIRE_MESSAGE(error.empty(), error);
	// Both devices streaming before the recording starts.
	for (int i = 0; i < 200 && (live.status(RecordingStream::Rgbd).frames < 3 || live.status(RecordingStream::Fisheye).frames < 3); i++) {
		std::this_thread::sleep_for(std::chrono::milliseconds(50));
	}
	REQUIRE_MESSAGE(live.status(RecordingStream::Rgbd).frames >= 3, live.status(RecordingStream::Rgbd).reason);
	REQUIRE_MESSAGE(live.status(RecordingStream::Fisheye).frames >= 3, live.status(RecordingStream::Fisheye).reason);

	const RecordingStatus opened = live.start_recording(folder.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	std::this_thread::sleep_for(std::chrono::seconds(5));
	const RecordingStatus closed = live.stop_recording();
	live.stop();
	REQUIRE_MESSAGE(closed.ok, closed.error);
	const RecordingQueueStatus written = live.recording_status();
	MESSAGE(written.written[0] << " RGB-D and " << written.written[1] << " fisheye frames written, " << written.dropped[0] + written.dropped[1]
									<< " dropped, " << written.megabytes_per_s << " MB/s");

	RecordingReader reader;
	const RecordingStatus read = reader.open(folder.string());
	REQUIRE_MESSAGE(read.ok, read.error);
	CHECK(reader.get_issues().empty());
	// 5 s of a 30 Hz camera: well over half its frames even on a busy machine.
	CHECK(reader.rgbd_count() >= 75);
	CHECK(reader.fisheye_count() >= 25);
	CHECK(reader.rgbd_count() == written.written[0]);
	CHECK(reader.fisheye_count() == written.written[1]);

	// Every recorded frame is one the rig delivered: same timestamp, same pixels, same device data;
	// and every delivered frame between the first and the last recorded one is in the recording
	// (or counted as dropped).
	size_t rgbd_between = 0;
	double previous_s = -1.0;
	for (size_t i = 0; i < reader.rgbd_count(); i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		REQUIRE_MESSAGE(frame.ok, frame.error);
		CHECK(frame.frame.timestamp_s > previous_s);
		previous_s = frame.frame.timestamp_s;
		const auto sent = rgbd_sent.find(frame.frame.timestamp_s);
		REQUIRE_MESSAGE(sent != rgbd_sent.end(), "recorded RGB-D frame " << i << " at " << frame.frame.timestamp_s << " s was never delivered");
		CHECK(same_pixels(frame.frame.rgb, sent->second.rgb));
		CHECK(same_pixels(frame.frame.depth_m, sent->second.depth_m));
		CHECK(frame.frame.capture.device_frame_id == sent->second.capture.device_frame_id);
		CHECK(frame.frame.capture.device_time_s == doctest::Approx(sent->second.capture.device_time_s).epsilon(1e-9));
		// And it is the .oni's frame its device counter names.
		const int64_t id = frame.frame.capture.device_frame_id;
		REQUIRE(id >= 1);
		REQUIRE(id <= ScriptedOni::FRAMES);
		CHECK_MESSAGE(ScriptedOni::is_frame(frame.frame, int(id - 1)), "recorded RGB-D frame " << i << " is not the .oni's frame " << id);
	}
	if (reader.rgbd_count() > 0) {
		const double first = reader.read_rgbd(0).frame.timestamp_s;
		for (const auto &[time_s, frame] : rgbd_sent) {
			rgbd_between += time_s >= first && time_s <= previous_s;
		}
		CHECK(rgbd_between == reader.rgbd_count() + written.dropped[0]);
	}

	previous_s = -1.0;
	for (size_t i = 0; i < reader.fisheye_count(); i++) {
		const FisheyeFrameResult frame = reader.read_fisheye(i);
		REQUIRE_MESSAGE(frame.ok, frame.error);
		CHECK(frame.frame.timestamp_s > previous_s);
		previous_s = frame.frame.timestamp_s;
		const auto sent = fisheye_sent.find(frame.frame.timestamp_s);
		REQUIRE_MESSAGE(sent != fisheye_sent.end(), "recorded fisheye frame " << i << " at " << frame.frame.timestamp_s << " s was never delivered");
		CHECK(same_pixels(frame.frame.image, sent->second.image));
		CHECK(frame.frame.capture.device_frame_id == sent->second.capture.device_frame_id);
		// The exposure set is the exposure every frame says it had (the Fake camera keeps it exactly).
		CHECK(frame.frame.capture.exposure_us == doctest::Approx(5000.0).epsilon(1e-6));
		CHECK(frame.frame.capture.gain == doctest::Approx(sent->second.capture.gain));
	}
	fs::remove_all(folder);
	fs::remove(oni);
}
