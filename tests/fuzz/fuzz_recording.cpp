// A whole recording through RecordingReader: open, then every frame of every stream read. The
// input is a bundle of files, "@@NAME\n" before each one's bytes, that replace files of a small
// valid recording the target writes once with RecordingWriter (names outside it are ignored, so
// nothing is written outside the scratch folder). Opening either succeeds or names a file; an
// RGB-D frame that reads has the rig's size and depth that is NaN or a positive distance; an HDR
// fisheye frame that reads holds only finite values.
//
// ROOMPROBE_FUZZ_SEED=FILE: writes the template itself as a bundle (the seed corpus's first entry)
// and exits.
#include "fuzz_common.h"

#include <recording/recording_reader.h>
#include <recording/recording_writer.h>

#include "synth_test_rig.h" // tests/core: the tests' small rig

#include <glm/gtc/quaternion.hpp>

#include <map>
#include <sstream>

using namespace roomprobe;

namespace {

namespace fs = std::filesystem;

constexpr size_t MAX_FRAMES_READ = 6; // per stream: enough to pass every kind of frame

Rig small_rig() { return small_test_rig(32, 24, 24, 24); }

// The template: 3 RGB-D frames, an 8-bit and an HDR fisheye frame, ground-truth poses, a room.
std::map<std::string, std::string> write_template(const fs::path &p_folder) {
	RoomInfo room;
	room.floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 5.0 }, { 0.0, 5.0 } };
	room.floorplan.ceiling_height_m = 2.5;
	room.initial_rgb_pose.translation = glm::dvec3(1.0, 1.5, 2.0);
	room.probes = { glm::dvec3(1.0, 1.0, 1.0) };
	RecordingWriter writer;
	fs::remove_all(p_folder);
	fuzz::require(writer.open(p_folder.string(), small_rig(), room).ok, "the template recording opens");
	for (int i = 0; i < 3; i++) {
		RgbdFrame frame;
		frame.timestamp_s = 10.0 + 0.033 * i;
		frame.rgb = cv::Mat(24, 32, CV_8UC3, cv::Scalar(40 * i, 90, 200));
		frame.depth_m = cv::Mat(24, 32, CV_32FC1, cv::Scalar(0.5 + 0.1 * i));
		frame.depth_m.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
		fuzz::require(writer.add_rgbd(frame).ok, "the template's RGB-D frame is written");
		Pose pose;
		pose.translation = glm::dvec3(0.1 * i, 1.5, 0.0);
		fuzz::require(writer.add_ground_truth_pose(RecordingStream::Rgbd, frame.timestamp_s, pose).ok, "the template's pose is written");
	}
	FisheyeFrame gray;
	gray.timestamp_s = 10.0;
	gray.image = cv::Mat(24, 24, CV_8UC1, cv::Scalar(120));
	fuzz::require(writer.add_fisheye(gray).ok, "the template's fisheye frame is written");
	FisheyeFrame hdr;
	hdr.timestamp_s = 10.05;
	hdr.hdr = true;
	hdr.image = cv::Mat(24, 24, CV_32FC3, cv::Scalar(0.5, 2.0, 30.0));
	fuzz::require(writer.add_fisheye(hdr).ok, "the template's HDR frame is written");
	fuzz::require(writer.close().ok, "the template recording closes");

	std::map<std::string, std::string> files;
	for (const fs::directory_entry &entry : fs::recursive_directory_iterator(p_folder)) {
		if (entry.is_regular_file()) {
			std::ifstream file(entry.path(), std::ios::binary);
			std::stringstream bytes;
			bytes << file.rdbuf();
			files[entry.path().lexically_relative(p_folder).generic_string()] = bytes.str();
		}
	}
	return files;
}

struct Template {
	fs::path folder;
	std::map<std::string, std::string> files; // relative path -> bytes
};

const Template &recording_template() {
	static const Template made = [] {
		Template t;
		t.folder = fuzz::scratch() / "recording";
		t.files = write_template(fuzz::scratch() / "template");
		fs::remove_all(t.folder);
		fs::copy(fuzz::scratch() / "template", t.folder, fs::copy_options::recursive);
		return t;
	}();
	return made;
}

void check_recording(const fs::path &p_folder) {
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_folder.string());
	if (!opened.ok) {
		fuzz::require(!opened.error.empty(), "a recording that fails to open says why");
		return;
	}
	const Rig &rig = reader.get_rig();
	for (size_t i = 0; i < std::min(reader.rgbd_count(), MAX_FRAMES_READ); i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		if (!frame.ok) {
			fuzz::require(!frame.error.empty(), "an RGB-D frame that fails says why");
			continue;
		}
		fuzz::require(frame.frame.rgb.cols == rig.rgb.width && frame.frame.rgb.rows == rig.rgb.height, "an RGB image has the rig's size");
		if (frame.frame.depth_m.empty()) {
			continue; // no depth at all: a calibration recording's frame keeps its RGB image
		}
		fuzz::require(frame.frame.depth_m.type() == CV_32FC1 && frame.frame.depth_m.size() == frame.frame.rgb.size(), "depth is registered to RGB");
		for (int y = 0; y < frame.frame.depth_m.rows; y++) {
			for (int x = 0; x < frame.frame.depth_m.cols; x++) {
				const float d = frame.frame.depth_m.at<float>(y, x);
				fuzz::require(std::isnan(d) || (d > 0.0f && std::isfinite(d)), "depth is no reading or a positive distance");
			}
		}
	}
	for (size_t i = 0; i < std::min(reader.fisheye_count(), MAX_FRAMES_READ); i++) {
		const FisheyeFrameResult frame = reader.read_fisheye(i);
		if (!frame.ok) {
			fuzz::require(!frame.error.empty(), "a fisheye frame that fails says why");
			continue;
		}
		fuzz::require(frame.frame.image.cols == rig.fisheye.width && frame.frame.image.rows == rig.fisheye.height, "a fisheye image has the rig's size");
		if (frame.frame.hdr) {
			fuzz::require(fuzz::all_finite(frame.frame.image), "an HDR frame holds only finite values");
		}
	}
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
	const char *seed = std::getenv("ROOMPROBE_FUZZ_SEED");
	if (seed != nullptr && *seed != '\0') {
		std::ofstream out(seed, std::ios::binary | std::ios::trunc);
		bool first = true;
		for (const auto &[name, bytes] : recording_template().files) {
			out << (first ? "@@" : "\n@@") << name << "\n" << bytes;
			first = false;
		}
		// Closed here: std::exit destroys no local, so the stream's last buffer was never
		// written (the seed was an empty file).
		out.close();
		std::exit(out ? 0 : 1);
	}
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const Template &t = recording_template();
	const std::string input(reinterpret_cast<const char *>(p_data), p_size);
	std::vector<std::string> replaced;
	for (size_t at = input.rfind("@@", 0) == 0 ? 0 : input.find("\n@@"); at != std::string::npos;) {
		const size_t name_start = at + (input.compare(at, 2, "@@") == 0 ? 2 : 3);
		const size_t name_end = input.find('\n', name_start);
		if (name_end == std::string::npos) {
			break;
		}
		const size_t next = input.find("\n@@", name_end);
		const std::string name = input.substr(name_start, name_end - name_start);
		const size_t body = name_end + 1;
		if (t.files.count(name) != 0) {
			const std::string bytes = input.substr(body, (next == std::string::npos ? input.size() : next) - body);
			fuzz::write_bytes(t.folder / name, reinterpret_cast<const uint8_t *>(bytes.data()), bytes.size());
			replaced.push_back(name);
		}
		at = next;
	}
	check_recording(t.folder);
	for (const std::string &name : replaced) { // back to the template for the next input
		const std::string &bytes = t.files.at(name);
		fuzz::write_bytes(t.folder / name, reinterpret_cast<const uint8_t *>(bytes.data()), bytes.size());
	}
	return 0;
}
