// A recording's capture.txt (what the live devices said about each frame: recording_reader.cpp's
// read_capture_list, reached through RecordingReader::open), in a small valid recording the target
// writes once with RecordingWriter, its frames carrying capture information. Any bytes leave the
// recording opening (a bad line is an issue naming capture.txt and its line, never a failure);
// a frame's capture holds what a device can have said (exposure in (0, 10 s], gain in [0, 1000],
// frame id -1 or more, NaN where unknown). The frames written again with their capture by
// RecordingWriter read back with the same capture.
//
// ROOMPROBE_FUZZ_SEED=FILE: writes the template's own capture.txt there (the seed corpus's first
// entry) and exits.
#include "fuzz_common.h"

#include <recording/recording_reader.h>
#include <recording/recording_writer.h>

#include "synth_test_rig.h" // tests/core: the tests' small rig

#include <sstream>
#include <vector>

using namespace roomprobe;

namespace {

namespace fs = std::filesystem;

Rig small_rig() { return small_test_rig(32, 24, 24, 24); }

RoomInfo small_room() {
	RoomInfo room;
	room.floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 5.0 }, { 0.0, 5.0 } };
	room.floorplan.ceiling_height_m = 2.5;
	room.initial_rgb_pose.translation = glm::dvec3(1.0, 1.5, 2.0);
	return room;
}

// Writes p_rgbd and p_fisheye as a recording into p_folder (replaced): their capture goes to
// capture.txt.
void write_recording(const fs::path &p_folder, const std::vector<RgbdFrame> &p_rgbd, const std::vector<FisheyeFrame> &p_fisheye) {
	fs::remove_all(p_folder);
	RecordingWriter writer;
	const RecordingStatus opened = writer.open(p_folder.string(), small_rig(), small_room());
	fuzz::require(opened.ok, "a recording opens for writing:", opened.error);
	for (const RgbdFrame &frame : p_rgbd) {
		const RecordingStatus added = writer.add_rgbd(frame);
		fuzz::require(added.ok, "an RGB-D frame is written:", added.error);
	}
	for (const FisheyeFrame &frame : p_fisheye) {
		const RecordingStatus added = writer.add_fisheye(frame);
		fuzz::require(added.ok, "a fisheye frame is written:", added.error);
	}
	const RecordingStatus closed = writer.close();
	fuzz::require(closed.ok, "a recording closes:", closed.error);
}

// The template: 3 RGB-D frames, 2 fisheye frames, each with a capture the way a live rig and
// the synthetic one write it.
fs::path recording_template() {
	static const fs::path folder = [] {
		std::vector<RgbdFrame> rgbd;
		for (int i = 0; i < 3; i++) {
			RgbdFrame frame;
			frame.timestamp_s = 10.0 + 0.033 * i;
			frame.rgb = cv::Mat(24, 32, CV_8UC3, cv::Scalar(40 * i, 90, 200));
			frame.depth_m = cv::Mat(24, 32, CV_32FC1, cv::Scalar(0.5 + 0.1 * i));
			frame.capture.device_time_s = 1234.5 + 0.033 * i;
			frame.capture.device_frame_id = 100 + i;
			rgbd.push_back(frame);
		}
		std::vector<FisheyeFrame> fisheye;
		for (int i = 0; i < 2; i++) {
			FisheyeFrame frame;
			frame.timestamp_s = 10.0 + 0.05 * i;
			frame.image = cv::Mat(24, 24, CV_8UC3, cv::Scalar(120, 60 * i, 30));
			frame.capture.exposure_us = 10000.0 * (i + 1);
			frame.capture.gain = 3.5 * i;
			if (i == 1) {
				frame.capture.device_time_s = 77.25;
				frame.capture.device_frame_id = 0;
			}
			fisheye.push_back(frame);
		}
		const fs::path path = fuzz::scratch() / "capture_template";
		write_recording(path, rgbd, fisheye);
		fuzz::require(fs::is_regular_file(path / "capture.txt"), "the template has a capture.txt");
		return path;
	}();
	return folder;
}

bool same(double p_a, double p_b) {
	return (std::isnan(p_a) && std::isnan(p_b)) || p_a == p_b;
}

bool same_capture(const CaptureInfo &p_a, const CaptureInfo &p_b) {
	return same(p_a.device_time_s, p_b.device_time_s) && p_a.device_frame_id == p_b.device_frame_id && same(p_a.exposure_us, p_b.exposure_us) &&
			same(p_a.gain, p_b.gain);
}

void check_capture(const CaptureInfo &p_capture) {
	fuzz::require(std::isnan(p_capture.exposure_us) || (p_capture.exposure_us > 0.0 && p_capture.exposure_us <= 1e7), "an exposure is unknown or in (0, 10 s]");
	fuzz::require(std::isnan(p_capture.gain) || (p_capture.gain >= 0.0 && p_capture.gain <= 1000.0), "a gain is unknown or in [0, 1000]");
	fuzz::require(p_capture.device_frame_id >= -1, "a device frame id is -1 or more");
	fuzz::require(std::isnan(p_capture.device_time_s) || std::isfinite(p_capture.device_time_s), "a device time is unknown or finite");
}

struct Read {
	std::vector<RgbdFrame> rgbd;
	std::vector<FisheyeFrame> fisheye;
	bool any_known = false;
};

Read read_all(const fs::path &p_folder, bool p_issues_allowed) {
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_folder.string());
	fuzz::require(opened.ok, "capture.txt never stops a recording opening:", opened.error);
	// The template has nothing else wrong: every issue is capture.txt's, named with its line (0:
	// the whole file). A capture.txt that RecordingWriter wrote has none.
	const std::string capture_path = (p_folder / "capture.txt").string();
	for (const RecordingIssue &issue : reader.get_issues()) {
		fuzz::require(p_issues_allowed, "a capture.txt the writer wrote reads without issues:", to_string(issue));
		fuzz::require(issue.file == capture_path && issue.line >= 0 && !issue.message.empty(), "an issue names capture.txt and says what is wrong:",
				to_string(issue));
	}
	fuzz::require(reader.rgbd_count() == 3 && reader.fisheye_count() == 2, "capture.txt leaves the frames as they are");
	Read read;
	for (size_t i = 0; i < reader.rgbd_count(); i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		fuzz::require(frame.ok, "an RGB-D frame of the template reads:", frame.error);
		check_capture(frame.frame.capture);
		read.any_known = read.any_known || frame.frame.capture.is_known();
		read.rgbd.push_back(frame.frame);
	}
	for (size_t i = 0; i < reader.fisheye_count(); i++) {
		const FisheyeFrameResult frame = reader.read_fisheye(i);
		fuzz::require(frame.ok, "a fisheye frame of the template reads:", frame.error);
		check_capture(frame.frame.capture);
		read.any_known = read.any_known || frame.frame.capture.is_known();
		read.fisheye.push_back(frame.frame);
	}
	return read;
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
	const char *seed = std::getenv("ROOMPROBE_FUZZ_SEED");
	if (seed != nullptr && *seed != '\0') {
		std::ifstream in(recording_template() / "capture.txt", std::ios::binary);
		std::ofstream out(seed, std::ios::binary | std::ios::trunc);
		out << in.rdbuf();
		out.close(); // std::exit destroys no local: flushed here
		std::exit(out ? 0 : 1);
	}
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const fs::path folder = recording_template();
	fuzz::write_bytes(folder / "capture.txt", p_data, p_size);
	const Read read = read_all(folder, true);
	if (!read.any_known) {
		return 0;
	}
	// Written again (the writer's capture.txt) and read back: the same capture, frame by frame.
	const fs::path again = fuzz::scratch() / "capture_again";
	write_recording(again, read.rgbd, read.fisheye);
	const Read reread = read_all(again, false);
	for (size_t i = 0; i < read.rgbd.size(); i++) {
		fuzz::require(same_capture(read.rgbd[i].capture, reread.rgbd[i].capture), "an RGB-D frame's capture written and read again is the same");
	}
	for (size_t i = 0; i < read.fisheye.size(); i++) {
		fuzz::require(same_capture(read.fisheye[i].capture, reread.fisheye[i].capture), "a fisheye frame's capture written and read again is the same");
	}
	return 0;
}
