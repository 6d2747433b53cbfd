// The OpenNI2 driver without a depth camera: listing, every way opening can
// fail, and playback of small recordings written here in OpenNI's .oni format.
// Live streaming (and registration, which recordings do not carry here) needs
// a Kinect or Xtion and is not tested.

#include "openni2/openni2_device.h"

#include <recording/oni_writer.h>

#include <doctest/doctest.h>

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

using namespace roomprobe::drivers;

namespace {

// Threads of this process now (/proc/self/task): OpenNI's player runs one per open recording.
size_t thread_count() {
	size_t count = 0;
	for ([[maybe_unused]] const auto &entry : std::filesystem::directory_iterator("/proc/self/task")) {
		count++;
	}
	return count;
}

namespace fs = std::filesystem;

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// A file under the temp directory, removed when the test is done.
class TempFile {
public:
	TempFile(const std::string &p_name, const std::string &p_bytes) :
			path(fs::temp_directory_path() / ("roomprobe_" + std::to_string(getpid()) + "_" + p_name)) {
		std::ofstream(path, std::ios::binary).write(p_bytes.data(), std::streamsize(p_bytes.size()));
	}
	TempFile(const TempFile &) = delete;
	TempFile &operator=(const TempFile &) = delete;
	~TempFile() {
		std::error_code error;
		fs::remove(path, error);
	}

	const fs::path path;
};

// A recording of 3 frames of 4x3 depth (p_depth_format) and colour, 0.1 s apart.
struct SmallRecording {
	static constexpr int WIDTH = 4;
	static constexpr int HEIGHT = 3;
	static constexpr int FRAMES = 3;
	static constexpr uint64_t FIRST_US = 1000;
	static constexpr uint64_t PERIOD_US = 100000; // Slack for a busy test machine.

	// Depth frame f, pixel i: (1000 + 100 f + i) mm; colour: (10 f + i, 2 i, 255 - i).
	static uint16_t depth_mm(int p_frame, int p_pixel) { return uint16_t(1000 + 100 * p_frame + p_pixel); }
	static uint8_t channel(int p_frame, int p_pixel, int p_channel) {
		return uint8_t(p_channel == 0 ? 10 * p_frame + p_pixel : p_channel == 1 ? 2 * p_pixel : 255 - p_pixel);
	}

	static void write(const fs::path &p_path, int p_depth_format) {
		roomprobe::OniWriter writer;
		writer.add_stream(roomprobe::OniWriter::DEPTH, WIDTH, HEIGHT, p_depth_format, FRAMES);
		writer.add_stream(roomprobe::OniWriter::COLOR, WIDTH, HEIGHT, 200, FRAMES);
		writer.begin_data();
		for (int f = 0; f < FRAMES; f++) {
			std::vector<uint16_t> depth(WIDTH * HEIGHT);
			std::vector<uint8_t> color(WIDTH * HEIGHT * 3);
			for (int i = 0; i < WIDTH * HEIGHT; i++) {
				depth[i] = uint16_t(depth_mm(f, i) * (p_depth_format == 101 ? 10 : 1));
				for (int c = 0; c < 3; c++) {
					color[i * 3 + c] = channel(f, i, c);
				}
			}
			const uint64_t timestamp_us = FIRST_US + uint64_t(f) * PERIOD_US;
			writer.add_frame(roomprobe::OniWriter::DEPTH, timestamp_us, uint32_t(f + 1), roomprobe::OniWriter::raw(depth));
			writer.add_frame(roomprobe::OniWriter::COLOR, timestamp_us, uint32_t(f + 1), roomprobe::OniWriter::raw(color));
		}
		REQUIRE(writer.save(p_path.string()).empty());
	}
};

} // namespace

TEST_CASE("openni2 driver: listing works; with no camera plugged in the list is empty, not an error") {
	for (int round = 0; round < 2; round++) { // The second round restarts OpenNI after its shutdown.
		DriverResult<std::vector<DeviceInfo>> devices = list_openni2_devices();
		REQUIRE_MESSAGE(devices.ok(), devices.error);
		for (const DeviceInfo &info : devices.value) {
			CHECK(info.backend == "openni2");
			CHECK_FALSE(info.id.empty());
		}
		// Without a USB bus in sight no camera can be there (this sandbox).
		if (!fs::exists("/dev/bus/usb")) {
			CHECK(devices.value.empty());
		} else {
			MESSAGE(devices.value.size() << " OpenNI2 device(s) plugged in");
		}
	}
}

TEST_CASE("openni2 driver: a session keeps OpenNI up across listings") {
	CHECK_FALSE(OpenNI2Session().is_active());
	DriverResult<OpenNI2Session> session = OpenNI2Session::start();
	REQUIRE_MESSAGE(session.ok(), session.error);
	CHECK(session.value.is_active());
	for (int round = 0; round < 3; round++) {
		CHECK(list_openni2_devices().ok());
	}
	OpenNI2Session moved = std::move(session.value);
	CHECK(moved.is_active());
}

TEST_CASE("openni2 driver: a missing .oni file fails with an error naming the path") {
	const std::string path = (fs::temp_directory_path() / "roomprobe_no_such_recording.oni").string();
	DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(path);
	CHECK_FALSE(opened.ok());
	CHECK(opened.value == nullptr);
	CHECK(contains(opened.error, "'" + path + "'"));
	CHECK(contains(opened.error, "not found"));
	MESSAGE(opened.error);
}

TEST_CASE("openni2 driver: a file that is not a recording fails with an error naming it") {
	SUBCASE("garbage bytes named .oni") {
		const TempFile garbage("garbage.oni", std::string("\x89PNG\r\n\x1a\n garbage, not a recording", 33));
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(garbage.path.string());
		CHECK_FALSE(opened.ok());
		CHECK(contains(opened.error, "'" + garbage.path.string() + "'"));
		CHECK(contains(opened.error, "not an .oni recording"));
		MESSAGE(opened.error);
	}
	SUBCASE("an existing file without the .oni extension is taken as a file too") {
		const TempFile text("notes.txt", "hello, depth camera\n");
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(text.path.string());
		CHECK_FALSE(opened.ok());
		CHECK(contains(opened.error, "OpenNI2 recording '" + text.path.string() + "'"));
		CHECK(contains(opened.error, "not an .oni recording"));
	}
	SUBCASE("a file shorter than the header") {
		const TempFile tiny("tiny.oni", "NI");
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(tiny.path.string());
		CHECK_FALSE(opened.ok());
		CHECK(contains(opened.error, "'" + tiny.path.string() + "'"));
		CHECK(contains(opened.error, "shorter"));
	}
	SUBCASE("the right header and garbage after it: OpenNI2 itself refuses it") {
		const TempFile truncated("truncated.oni", std::string("NI10") + std::string(60, '\x07'));
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(truncated.path.string());
		CHECK_FALSE(opened.ok());
		CHECK(contains(opened.error, "'" + truncated.path.string() + "'"));
		CHECK(contains(opened.error, "cannot play"));
		MESSAGE(opened.error);
	}
	SUBCASE("a directory") {
		const fs::path directory = fs::temp_directory_path();
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(directory.string());
		CHECK_FALSE(opened.ok());
		CHECK(contains(opened.error, "not a regular file"));
	}
}

TEST_CASE("openni2 driver: device URIs that are not there fail with an error naming them") {
	DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open("1d27/0601@9/99");
	CHECK_FALSE(opened.ok());
	CHECK(contains(opened.error, "OpenNI2 device '1d27/0601@9/99'"));
	CHECK(contains(opened.error, "not found"));
	MESSAGE(opened.error);

	DriverResult<std::unique_ptr<OpenNI2Device>> empty = OpenNI2Device::open("");
	CHECK_FALSE(empty.ok());
	CHECK(contains(empty.error, "empty URI"));

	// OpenNI2's DummyDevice driver segfaults on open: refused before OpenNI sees it.
	DriverResult<std::unique_ptr<OpenNI2Device>> dummy = OpenNI2Device::open("Dummy");
	CHECK_FALSE(dummy.ok());
	CHECK(contains(dummy.error, "'Dummy'"));
	CHECK(contains(dummy.error, "refused"));
}

TEST_CASE("openni2 driver: a recording plays back depth in millimetres and RGB colour with their timestamps") {
	for (const int depth_format : { 100, 101 }) { // OpenNI's 1 mm and 100 um depth formats.
		CAPTURE(depth_format);
		const TempFile recording("recording_" + std::to_string(depth_format) + ".oni", "");
		SmallRecording::write(recording.path, depth_format);
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(recording.path.string());
		REQUIRE_MESSAGE(opened.ok(), opened.error);
		OpenNI2Device &device = *opened.value;
		CHECK(device.is_file());
		CHECK(device.has_depth());
		CHECK(device.has_color());
		CHECK(device.get_info().backend == "openni2");
		CHECK(device.get_info().id == recording.path.string());

		// Playback runs at the recorded pace and gives every frame once, in order.
		const auto started = std::chrono::steady_clock::now();
		uint64_t last_depth_ns = 0;
		int frames_read = 0;
		std::string end_error;
		while (frames_read <= SmallRecording::FRAMES) {
			DriverResult<RgbdGrab> frame = device.grab(500);
			if (!frame.ok()) {
				end_error = frame.error;
				break;
			}
			const DepthFrame &depth = frame.value.depth;
			const ColorFrame &color = frame.value.color;
			const int f = depth.frame_index - 1; // The recording numbers frames from 1.
			CAPTURE(f);
			REQUIRE(f == frames_read);
			CHECK(color.frame_index == depth.frame_index);
			REQUIRE(depth.width == SmallRecording::WIDTH);
			REQUIRE(depth.height == SmallRecording::HEIGHT);
			REQUIRE(depth.depth_mm.size() == size_t(SmallRecording::WIDTH * SmallRecording::HEIGHT));
			REQUIRE(color.width == SmallRecording::WIDTH);
			REQUIRE(color.height == SmallRecording::HEIGHT);
			REQUIRE(color.rgb.size() == size_t(SmallRecording::WIDTH * SmallRecording::HEIGHT * 3));
			bool depth_matches = true;
			bool color_matches = true;
			for (int i = 0; i < SmallRecording::WIDTH * SmallRecording::HEIGHT; i++) {
				depth_matches = depth_matches && depth.depth_mm[i] == SmallRecording::depth_mm(f, i);
				for (int c = 0; c < 3; c++) {
					color_matches = color_matches && color.rgb[i * 3 + c] == SmallRecording::channel(f, i, c);
				}
			}
			CHECK(depth_matches);
			CHECK(color_matches);
			CHECK_FALSE(depth.registered_to_color);
			CHECK(depth.timestamp_ns == (SmallRecording::FIRST_US + uint64_t(f) * SmallRecording::PERIOD_US) * 1000);
			CHECK(color.timestamp_ns == depth.timestamp_ns);
			CHECK(depth.timestamp_ns > last_depth_ns);
			CHECK(depth.host_timestamp_ns > 0);
			last_depth_ns = depth.timestamp_ns;
			frames_read++;
		}
		CHECK(frames_read == SmallRecording::FRAMES);
		// The last frame is held until its time: FRAMES - 1 periods after the first.
		const double elapsed_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - started).count();
		CHECK(elapsed_us >= double((SmallRecording::FRAMES - 1) * SmallRecording::PERIOD_US));

		// No repeat: after the last frame, grabbing says the recording has ended.
		CHECK(contains(end_error, "'" + recording.path.string() + "'"));
		CHECK(contains(end_error, "end of the recording"));
		MESSAGE(end_error);
	}
}

TEST_CASE("openni2 driver: two devices open at once share OpenNI, which outlives the first") {
	const TempFile first_file("first.oni", "");
	const TempFile second_file("second.oni", "");
	SmallRecording::write(first_file.path, 100);
	SmallRecording::write(second_file.path, 100);
	DriverResult<std::unique_ptr<OpenNI2Device>> first = OpenNI2Device::open(first_file.path.string());
	DriverResult<std::unique_ptr<OpenNI2Device>> second = OpenNI2Device::open(second_file.path.string());
	REQUIRE_MESSAGE(first.ok(), first.error);
	REQUIRE_MESSAGE(second.ok(), second.error);
	first.value.reset();
	DriverResult<DepthFrame> frame = second.value->grab_depth(2000);
	REQUIRE_MESSAGE(frame.ok(), frame.error);
	CHECK(frame.value.frame_index == 1); // every frame is played: the first comes first
	CHECK(frame.value.depth_mm[0] == SmallRecording::depth_mm(0, 0));
	CHECK(list_openni2_devices().ok());
}

// libOniFile's player thread used to crash when a recording was closed while it ran (issue #12).
// Played in OpenNI's manual mode it waits, parked, for each read; closing must end it every time.
TEST_CASE("openni2 driver: closing a recording mid-stream ends its player thread, again and again") {
	const TempFile file("cycles.oni", "");
	SmallRecording::write(file.path, 100);
	const DriverResult<OpenNI2Session> session = OpenNI2Session::start(); // OpenNI's own threads stay up
	REQUIRE_MESSAGE(session.ok(), session.error);
	const size_t threads_before = thread_count();
	for (int cycle = 0; cycle < 40; cycle++) {
		CAPTURE(cycle);
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(file.path.string());
		REQUIRE_MESSAGE(opened.ok(), opened.error);
		CHECK(thread_count() > threads_before); // its player
		// Close after 0, 1 or 2 frames: idle, between frames, mid-recording.
		for (int f = 0; f < cycle % 3; f++) {
			DriverResult<RgbdGrab> frame = opened.value->grab(1000);
			REQUIRE_MESSAGE(frame.ok(), frame.error);
			CHECK(frame.value.depth.frame_index == f + 1);
		}
		opened.value.reset();
		// Closing joins the player; its task can linger in /proc for a moment after the join.
		const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
		while (thread_count() != threads_before && std::chrono::steady_clock::now() < deadline) {
			std::this_thread::sleep_for(std::chrono::milliseconds(5));
		}
		CHECK(thread_count() == threads_before);
	}
}
