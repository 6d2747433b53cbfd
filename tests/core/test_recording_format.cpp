// RoomProbe recordings (docs/recording-format.md): writing one and reading it back exactly, the
// writer's refusals, and reading damaged recordings (issues naming file and line, playback of
// the other frames going on; fatal errors only for an unusable rig, room or index).

#include "eval/evaluate.h"
#include "io/exr_write.h"
#include "io/raw_frame.h"
#include "types/cubemap_layout.h"
#include "recording/recording_io.h"
#include "recording/recording_reader.h"
#include "recording/recording_writer.h"
#include "recording/room_file.h"

#include "recording_test_issues.h"

#include "test_images.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

using namespace roomprobe;
namespace fs = std::filesystem;

using recording_test::all_issues;

namespace {

constexpr int RGB_WIDTH = 64;
constexpr int RGB_HEIGHT = 48;
constexpr int FISHEYE_SIZE = 40;
constexpr int CUBE_SIZE = 8;
constexpr double FISHEYE_OFFSET_S = 0.005;

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

bool ends_with(const std::string &p_text, const std::string &p_end) {
	return p_text.size() >= p_end.size() && p_text.compare(p_text.size() - p_end.size(), p_end.size(), p_end) == 0;
}

// A fresh, empty-to-be folder under build/ for one test.
fs::path scratch_folder(const std::string &p_name) {
	const fs::path folder = fs::path("build") / "test-recording" / p_name;
	std::error_code ec;
	fs::remove_all(folder, ec);
	fs::create_directories(folder.parent_path(), ec);
	return folder;
}

std::string read_text(const fs::path &p_path) {
	std::ifstream file(p_path, std::ios::binary);
	std::stringstream text;
	text << file.rdbuf();
	return text.str();
}

void write_text(const fs::path &p_path, const std::string &p_text) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file << p_text;
}

void truncate_to_half(const fs::path &p_path) {
	const std::string bytes = read_text(p_path);
	write_text(p_path, bytes.substr(0, bytes.size() / 2));
}

Rig make_rig() {
	Rig rig;
	rig.rgb.width = RGB_WIDTH;
	rig.rgb.height = RGB_HEIGHT;
	rig.rgb.fx = 50.0;
	rig.rgb.fy = 50.0;
	rig.rgb.cx = 31.5;
	rig.rgb.cy = 23.5;
	rig.depth_scale_m = 0.001;
	rig.fisheye.width = FISHEYE_SIZE;
	rig.fisheye.height = FISHEYE_SIZE;
	rig.fisheye.xi = 1.0;
	rig.fisheye.fx = 20.0;
	rig.fisheye.fy = 20.0;
	rig.fisheye.cx = 19.5;
	rig.fisheye.cy = 19.5;
	rig.fisheye.circle_cx = 19.5;
	rig.fisheye.circle_cy = 19.5;
	rig.fisheye.circle_radius = 19.0;
	rig.rgb_from_fisheye.translation = glm::dvec3(0.0, -0.08, 0.02);
	rig.fisheye_time_offset_s = FISHEYE_OFFSET_S;
	return rig;
}

RoomInfo make_room() {
	RoomInfo room;
	room.floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 5.0 }, { 0.0, 5.0 } };
	room.floorplan.ceiling_height_m = 2.5;
	room.initial_rgb_pose.rotation = glm::angleAxis(0.3, glm::normalize(glm::dvec3(0.0, 1.0, 0.2)));
	room.initial_rgb_pose.translation = glm::dvec3(1.0, 1.5, 2.0);
	room.probes = { glm::dvec3(1.0, 1.0, 1.0), glm::dvec3(2.0, 1.25, 3.5) };
	return room;
}

double rgb_time(int p_frame) {
	return 10.0 + 0.033 * p_frame;
}

cv::Vec3b rgb_pattern(int p_frame, int p_x, int p_y) {
	return cv::Vec3b(uchar((p_x * 4 + p_frame) & 255), uchar(p_y * 5), uchar(100 + p_frame));
}

// Depth in whole millimetres; (0, 0) has no reading.
int depth_units(int p_frame, int p_x, int p_y) {
	return p_x == 0 && p_y == 0 ? 0 : 500 + p_x + p_y + 100 * p_frame;
}

RgbdFrame make_rgbd(int p_frame) {
	RgbdFrame frame;
	frame.timestamp_s = rgb_time(p_frame);
	if (p_frame == 2) {
		frame.depth_timestamp_s = rgb_time(p_frame) + 0.004; // within the association window
	}
	frame.rgb = cv::Mat(RGB_HEIGHT, RGB_WIDTH, CV_8UC3);
	frame.depth_m = cv::Mat(RGB_HEIGHT, RGB_WIDTH, CV_32FC1);
	for (int y = 0; y < RGB_HEIGHT; y++) {
		for (int x = 0; x < RGB_WIDTH; x++) {
			frame.rgb.at<cv::Vec3b>(y, x) = rgb_pattern(p_frame, x, y);
			const int units = depth_units(p_frame, x, y);
			frame.depth_m.at<float>(y, x) = units == 0 ? std::numeric_limits<float>::quiet_NaN() : float(units * 0.001);
		}
	}
	return frame;
}

uchar gray_pattern(int p_x, int p_y) {
	return uchar((p_x * 3 + p_y * 2) & 255);
}

cv::Vec3f hdr_pattern(int p_x, int p_y) {
	return cv::Vec3f(0.01f + 0.37f * float(p_x), 100.5f * float(p_y), 3000.0f + float(p_x * p_y));
}

FisheyeFrame make_gray_fisheye() {
	FisheyeFrame frame;
	frame.timestamp_s = 9.99;
	frame.image = cv::Mat(FISHEYE_SIZE, FISHEYE_SIZE, CV_8UC1);
	for (int y = 0; y < FISHEYE_SIZE; y++) {
		for (int x = 0; x < FISHEYE_SIZE; x++) {
			frame.image.at<uchar>(y, x) = gray_pattern(x, y);
		}
	}
	return frame;
}

FisheyeFrame make_hdr_fisheye() {
	FisheyeFrame frame;
	frame.timestamp_s = 10.05;
	frame.hdr = true;
	frame.image = cv::Mat(FISHEYE_SIZE, FISHEYE_SIZE, CV_32FC3);
	for (int y = 0; y < FISHEYE_SIZE; y++) {
		for (int x = 0; x < FISHEYE_SIZE; x++) {
			frame.image.at<cv::Vec3f>(y, x) = hdr_pattern(x, y);
		}
	}
	return frame;
}

Pose gt_rgb_pose(int p_frame) {
	Pose pose;
	pose.rotation = glm::angleAxis(0.1 * p_frame, glm::normalize(glm::dvec3(1.0, 2.0, 3.0)));
	pose.translation = glm::dvec3(p_frame, 1.5, -0.5 * p_frame);
	return pose;
}

// Face f of the ground-truth cubemap is filled with this colour (exact in half floats).
cv::Vec3f face_colour(int p_face) {
	return cv::Vec3f(0.5f * float(p_face + 1), 2.0f * float(p_face + 1), 100.0f * float(p_face + 1));
}

cv::Vec3b face_colour_8bit(int p_face) {
	return cv::Vec3b(uchar(p_face * 40), uchar(255 - p_face * 40), 7);
}

const cv::Vec3f CUBE_MARKER(1234.0f, 0.125f, 3.0f); // at pixel (u 5, v 2) of +Z

// Writes the reference recording: p_rgbd_frames RGB-D frames, a gray and an HDR fisheye frame,
// ground-truth trajectories of both cameras and one ground-truth cubemap. PNG frames unless told:
// the damaged-recording cases edit PNG files (recordings made before raw frames play on); the
// raw-frame cases ask for FrameFormat::Zstd, the writer's default.
void write_recording(const fs::path &p_folder, int p_rgbd_frames = 3, FrameFormat p_format = FrameFormat::Png) {
	RecordingWriter writer;
	RecordingWriteOptions options;
	options.frame_format = p_format;
	const RecordingStatus opened = writer.open(p_folder.string(), make_rig(), make_room(), options);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	// Interleaved as they would arrive; each stream keeps its own order.
	CHECK(writer.add_fisheye(make_gray_fisheye()).ok);
	for (int i = 0; i < p_rgbd_frames; i++) {
		const RecordingStatus added = writer.add_rgbd(make_rgbd(i));
		CHECK_MESSAGE(added.ok, added.error);
		CHECK(writer.add_ground_truth_pose(RecordingStream::Rgbd, rgb_time(i), gt_rgb_pose(i)).ok);
		if (i == 1) {
			const RecordingStatus hdr = writer.add_fisheye(make_hdr_fisheye());
			CHECK_MESSAGE(hdr.ok, hdr.error);
		}
	}
	CHECK(writer.add_ground_truth_pose(RecordingStream::Fisheye, 9.99, gt_rgb_pose(5)).ok);
	CHECK(writer.add_ground_truth_pose(RecordingStream::Fisheye, 10.05, gt_rgb_pose(6)).ok);

	CubemapFaces faces;
	CubemapFaces ldr_faces;
	for (int f = 0; f < 6; f++) {
		faces[f] = cv::Mat(CUBE_SIZE, CUBE_SIZE, CV_32FC3, cv::Scalar(face_colour(f)[0], face_colour(f)[1], face_colour(f)[2]));
		ldr_faces[f] = cv::Mat(CUBE_SIZE, CUBE_SIZE, CV_8UC3, cv::Scalar(face_colour_8bit(f)[0], face_colour_8bit(f)[1], face_colour_8bit(f)[2]));
	}
	faces[CUBEMAP_POSITIVE_Z].at<cv::Vec3f>(2, 5) = CUBE_MARKER;
	const RecordingStatus cube = writer.add_ground_truth_cubemap(10.033, 1, faces, ldr_faces);
	CHECK_MESSAGE(cube.ok, cube.error);
	const RecordingStatus closed = writer.close();
	REQUIRE_MESSAGE(closed.ok, closed.error);
}

const RecordingIssue *find_issue(const RecordingReader &p_reader, const std::string &p_part) {
	for (const RecordingIssue &issue : p_reader.get_issues()) {
		if (contains(issue.message, p_part)) {
			return &issue;
		}
	}
	return nullptr;
}

// Every frame left in the recording reads, and the event list holds them all.
void check_plays_on(const RecordingReader &p_reader, size_t p_rgbd, size_t p_fisheye) {
	CHECK(p_reader.rgbd_count() == p_rgbd);
	CHECK(p_reader.fisheye_count() == p_fisheye);
	for (size_t i = 0; i < p_reader.rgbd_count(); i++) {
		const RgbdFrameResult frame = p_reader.read_rgbd(i);
		CHECK_MESSAGE(frame.ok, frame.error);
	}
	for (size_t i = 0; i < p_reader.fisheye_count(); i++) {
		const FisheyeFrameResult frame = p_reader.read_fisheye(i);
		CHECK_MESSAGE(frame.ok, frame.error);
	}
	CHECK(p_reader.get_events().size() == p_rgbd + p_fisheye);
}

// Replaces line p_line (1-based) of a text file.
void replace_line(const fs::path &p_path, int p_line, const std::string &p_text) {
	std::istringstream in(read_text(p_path));
	std::string out;
	std::string line;
	for (int number = 1; std::getline(in, line); number++) {
		out += (number == p_line ? p_text : line) + "\n";
	}
	write_text(p_path, out);
}

} // namespace

// ------------------------------------------------------------------------------------ round trip

TEST_CASE("recording round trip: rig, room, frames, timestamps and pixels read back exactly, PNG and raw frames") {
	for (const FrameFormat format : { FrameFormat::Png, FrameFormat::Zstd }) {
		CAPTURE(frame_format_name(format));
		const fs::path folder = scratch_folder(std::string("roundtrip_") + frame_format_name(format));
		write_recording(folder, 3, format);

		RecordingReader reader;
		const RecordingStatus opened = reader.open(folder.string());
		REQUIRE_MESSAGE(opened.ok, opened.error);
		CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));

		// Rig and room.
		const Rig &rig = reader.get_rig();
		CHECK(rig.rgb.width == RGB_WIDTH);
		CHECK(rig.rgb.fx == 50.0);
		CHECK(rig.fisheye.width == FISHEYE_SIZE);
		CHECK(rig.fisheye_time_offset_s == FISHEYE_OFFSET_S);
		REQUIRE(reader.has_room());
		const RoomInfo &room = reader.get_room();
		const RoomInfo expected_room = make_room();
		REQUIRE(room.floorplan.points.size() == 4);
		CHECK(room.floorplan.points[2].x == 4.0);
		CHECK(room.floorplan.points[2].y == 5.0);
		CHECK(room.floorplan.ceiling_height_m == 2.5);
		CHECK(room.initial_rgb_pose.rotation.w == doctest::Approx(expected_room.initial_rgb_pose.rotation.w).epsilon(1e-15));
		CHECK(room.initial_rgb_pose.rotation.y == doctest::Approx(expected_room.initial_rgb_pose.rotation.y).epsilon(1e-15));
		CHECK(room.initial_rgb_pose.translation.z == 2.0);
		REQUIRE(room.probes.size() == 2);
		CHECK(room.probes[1].y == 1.25);

		// RGB-D frames: timestamps, exact RGB values in R, G, B order, depth in metres.
		REQUIRE(reader.rgbd_count() == 3);
		for (int i = 0; i < 3; i++) {
			const RgbdFrameResult result = reader.read_rgbd(size_t(i));
			REQUIRE_MESSAGE(result.ok, result.error);
			const RgbdFrame &frame = result.frame;
			CHECK(frame.timestamp_s == rgb_time(i));
			CHECK(frame.depth_timestamp_s == (i == 2 ? rgb_time(i) + 0.004 : rgb_time(i)));
			REQUIRE(frame.rgb.type() == CV_8UC3);
			REQUIRE(frame.depth_m.type() == CV_32FC1);
			REQUIRE(frame.rgb.size() == cv::Size(RGB_WIDTH, RGB_HEIGHT));
			int rgb_mismatches = 0;
			int depth_mismatches = 0;
			for (int y = 0; y < RGB_HEIGHT; y++) {
				for (int x = 0; x < RGB_WIDTH; x++) {
					rgb_mismatches += frame.rgb.at<cv::Vec3b>(y, x) != rgb_pattern(i, x, y);
					const int units = depth_units(i, x, y);
					const float depth = frame.depth_m.at<float>(y, x);
					depth_mismatches += units == 0 ? !std::isnan(depth) : depth != float(units * 0.001);
				}
			}
			CHECK(rgb_mismatches == 0);
			CHECK(depth_mismatches == 0);
			CHECK(frame.rgb.at<cv::Vec3b>(0, 1)[0] == uchar(4 + i)); // red first
			CHECK(frame.depth_m.at<float>(3, 2) == doctest::Approx(0.505 + 0.1 * i).epsilon(1e-6));
		}

		// Fisheye: an 8-bit gray PNG and an HDR EXR, each on the fisheye clock.
		REQUIRE(reader.fisheye_count() == 2);
		const FisheyeFrameResult gray = reader.read_fisheye(0);
		REQUIRE_MESSAGE(gray.ok, gray.error);
		CHECK(gray.frame.timestamp_s == 9.99);
		CHECK_FALSE(gray.frame.hdr);
		REQUIRE(gray.frame.image.type() == CV_8UC1);
		int gray_mismatches = 0;
		for (int y = 0; y < FISHEYE_SIZE; y++) {
			for (int x = 0; x < FISHEYE_SIZE; x++) {
				gray_mismatches += gray.frame.image.at<uchar>(y, x) != gray_pattern(x, y);
			}
		}
		CHECK(gray_mismatches == 0);
		const FisheyeFrameResult hdr = reader.read_fisheye(1);
		REQUIRE_MESSAGE(hdr.ok, hdr.error);
		CHECK(hdr.frame.timestamp_s == 10.05);
		CHECK(hdr.frame.hdr);
		REQUIRE(hdr.frame.image.type() == CV_32FC3);
		CHECK(reader.get_fisheye_ref(1).path == "fisheye/000001.exr");
		double worst_relative = 0.0;
		for (int y = 0; y < FISHEYE_SIZE; y++) {
			for (int x = 0; x < FISHEYE_SIZE; x++) {
				const cv::Vec3f expected = hdr_pattern(x, y);
				const cv::Vec3f actual = hdr.frame.image.at<cv::Vec3f>(y, x);
				for (int c = 0; c < 3; c++) {
					const double relative = std::abs(double(actual[c]) - double(expected[c])) / std::max(1e-3, std::abs(double(expected[c])));
					worst_relative = std::max(worst_relative, relative);
				}
			}
		}
		CHECK(worst_relative <= 1.0 / 2048.0); // half: 11 significant bits, rounded to nearest

		// Playback order on the RGB-D clock: fisheye 9.99 + 0.005, rgbd 10.0, 10.033, fisheye 10.055, rgbd 10.066.
		const std::vector<PlaybackEvent> &events = reader.get_events();
		REQUIRE(events.size() == 5);
		CHECK(events[0].stream == RecordingStream::Fisheye);
		CHECK(events[0].index == 0);
		CHECK(events[0].time_s == doctest::Approx(9.99 + FISHEYE_OFFSET_S).epsilon(1e-12));
		CHECK(events[1].stream == RecordingStream::Rgbd);
		CHECK(events[1].index == 0);
		CHECK(events[2].stream == RecordingStream::Rgbd);
		CHECK(events[2].index == 1);
		CHECK(events[3].stream == RecordingStream::Fisheye);
		CHECK(events[3].index == 1);
		CHECK(events[4].stream == RecordingStream::Rgbd);
		CHECK(events[4].index == 2);
		for (size_t i = 1; i < events.size(); i++) {
			CHECK(events[i - 1].time_s <= events[i].time_s);
		}

		// Ground-truth trajectories.
		REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
		REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Fisheye));
		const std::vector<TimedPose> &rgb_poses = reader.ground_truth_trajectory(RecordingStream::Rgbd).get_samples();
		REQUIRE(rgb_poses.size() == 3);
		for (int i = 0; i < 3; i++) {
			const Pose expected = gt_rgb_pose(i);
			CHECK(rgb_poses[size_t(i)].t_s == rgb_time(i));
			CHECK(rgb_poses[size_t(i)].world_from_camera.translation.x == doctest::Approx(expected.translation.x).epsilon(1e-12));
			CHECK(rgb_poses[size_t(i)].world_from_camera.translation.z == doctest::Approx(expected.translation.z).epsilon(1e-12));
			CHECK(rgb_poses[size_t(i)].world_from_camera.rotation.x == doctest::Approx(expected.rotation.x).epsilon(1e-12));
			CHECK(rgb_poses[size_t(i)].world_from_camera.rotation.w == doctest::Approx(expected.rotation.w).epsilon(1e-12));
		}
		const std::vector<TimedPose> &fisheye_poses = reader.ground_truth_trajectory(RecordingStream::Fisheye).get_samples();
		REQUIRE(fisheye_poses.size() == 2);
		CHECK(fisheye_poses[1].t_s == 10.05);
		CHECK(fisheye_poses[1].world_from_camera.translation.x == doctest::Approx(6.0));
	}
}

// A float R, G, B EXR of any values, NaN and infinity included (write_exr_rgb refuses those).
static void write_any_exr(const std::string &p_path, const cv::Mat &p_rgb) {
	Imf::Header header(p_rgb.cols, p_rgb.rows);
	Imf::FrameBuffer buffer;
	const char *names[3] = { "R", "G", "B" };
	for (int c = 0; c < 3; c++) {
		header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
		buffer.insert(names[c], Imf::Slice(Imf::FLOAT, const_cast<char *>(reinterpret_cast<const char *>(p_rgb.ptr<float>() + c)), sizeof(float) * 3, p_rgb.step[0]));
	}
	REQUIRE(write_exr(p_path, header, buffer, p_rgb.rows) == "");
}

TEST_CASE("damaged recording: a ground-truth cubemap holding NaN, infinity or negative radiance is refused, naming the file") {
	// Issue #38: an all-NaN truth scored as a perfect map.
	const fs::path folder = scratch_folder("cubemap_nan");
	write_recording(folder);
	const std::string exr = (folder / "groundtruth/cubemaps/000000.exr").string();
	cv::Mat strip(6 * CUBE_SIZE, CUBE_SIZE, CV_32FC3, cv::Scalar::all(0.5));
	for (const float bad : { std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f }) {
		CAPTURE(bad);
		strip.at<cv::Vec3f>(3, 2)[1] = bad;
		write_any_exr(exr, strip);
		RecordingReader reader;
		REQUIRE(reader.open(folder.string()).ok);
		const GroundTruthCubemapResult result = reader.ground_truth_cubemap(0);
		CHECK_FALSE(result.ok);
		CHECK(contains(result.error, exr + ": 1 values are NaN, infinite or negative"));
	}
	strip.setTo(cv::Scalar::all(std::numeric_limits<float>::quiet_NaN()));
	write_any_exr(exr, strip);
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK(contains(reader.ground_truth_cubemap(0).error, std::to_string(6 * CUBE_SIZE * CUBE_SIZE * 3) + " values are NaN"));
}

TEST_CASE("recording round trip: a ground-truth cubemap keeps its faces in place") {
	const fs::path folder = scratch_folder("cubemap");
	write_recording(folder);
	RecordingReader reader;
	const RecordingStatus opened = reader.open(folder.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	REQUIRE(reader.ground_truth_cubemap_count() == 1);
	CHECK(reader.get_ground_truth_cubemap_ref(0).path == "groundtruth/cubemaps/000000.exr");

	const GroundTruthCubemapResult result = reader.ground_truth_cubemap(0);
	REQUIRE_MESSAGE(result.ok, result.error);
	const GroundTruthCubemap &cube = result.cubemap;
	CHECK(cube.timestamp_s == 10.033);
	CHECK(cube.probe_index == 1);
	CHECK(cube.position.z == 3.5);
	for (int f = 0; f < 6; f++) {
		REQUIRE(cube.faces[f].type() == CV_32FC3);
		REQUIRE(cube.faces[f].size() == cv::Size(CUBE_SIZE, CUBE_SIZE));
		CHECK(cube.faces[f].at<cv::Vec3f>(0, 0) == face_colour(f));
		CHECK(cube.faces[f].at<cv::Vec3f>(CUBE_SIZE - 1, CUBE_SIZE - 1) == face_colour(f));
		REQUIRE(cube.ldr_faces[f].type() == CV_8UC3);
		CHECK(cube.ldr_faces[f].at<cv::Vec3b>(4, 4) == face_colour_8bit(f));
	}
	CHECK(cube.faces[CUBEMAP_POSITIVE_Z].at<cv::Vec3f>(2, 5) == CUBE_MARKER);
	CHECK(cube.faces[CUBEMAP_POSITIVE_Z].at<cv::Vec3f>(5, 2) == face_colour(CUBEMAP_POSITIVE_Z));

	// Looking up world directions finds the colour written to the face for that axis.
	const struct {
		glm::dvec3 direction;
		int face;
	} axes[6] = { { { 1, 0, 0 }, CUBEMAP_POSITIVE_X }, { { -1, 0, 0 }, CUBEMAP_NEGATIVE_X }, { { 0, 1, 0 }, CUBEMAP_POSITIVE_Y },
		{ { 0, -1, 0 }, CUBEMAP_NEGATIVE_Y }, { { 0, 0, 1 }, CUBEMAP_POSITIVE_Z }, { { 0, 0, -1 }, CUBEMAP_NEGATIVE_Z } };
	for (const auto &axis : axes) {
		int face = -1;
		double u = 0.0;
		double v = 0.0;
		cubemap_face_pixel(axis.direction, CUBE_SIZE, &face, &u, &v);
		CHECK(face == axis.face);
		CHECK(cube.faces[face].at<cv::Vec3f>(int(v), int(u)) == face_colour(axis.face));
	}
	// The marker's pixel centre maps to a direction on +Z: s = 2 * 5.5 / 8 - 1, t = 2 * 2.5 / 8 - 1.
	const glm::dvec3 marker = cubemap_direction(CUBEMAP_POSITIVE_Z, 5.0, 2.0, CUBE_SIZE);
	CHECK(marker.x / marker.z == doctest::Approx(0.375));
	CHECK(marker.y / marker.z == doctest::Approx(0.375));

	// The file itself: one EXR, 8 wide and 48 tall, faces top to bottom +X -X +Y -Y +Z -Z.
	cv::Mat strip;
	const std::string error = recording_io::read_exr_rgb((folder / "groundtruth/cubemaps/000000.exr").string(), &strip);
	REQUIRE_MESSAGE(error.empty(), error);
	CHECK(strip.cols == CUBE_SIZE);
	CHECK(strip.rows == 6 * CUBE_SIZE);
	for (int f = 0; f < 6; f++) {
		CHECK(strip.at<cv::Vec3f>(f * CUBE_SIZE + 1, 1) == face_colour(f));
	}
	CHECK(strip.at<cv::Vec3f>(CUBEMAP_POSITIVE_Z * CUBE_SIZE + 2, 5) == CUBE_MARKER);
	CHECK(fs::exists(folder / "groundtruth/cubemaps/000000.png"));
}

TEST_CASE("recording files: indexes are TUM-like text, room.yaml and rig.yaml load on their own") {
	const fs::path folder = scratch_folder("files");
	write_recording(folder);
	const std::string rgb = read_text(folder / "rgb.txt");
	CHECK(contains(rgb, "\n10 rgb/000000.png\n"));
	CHECK(contains(rgb, "\n10.033 rgb/000001.png\n"));
	CHECK(rgb.front() == '#');
	CHECK(contains(read_text(folder / "depth.txt"), "\n10.07 depth/000002.png\n"));
	CHECK(contains(read_text(folder / "fisheye.txt"), "\n9.99 fisheye/000000.png\n10.05 fisheye/000001.exr\n"));
	CHECK(contains(read_text(folder / "groundtruth/cubemaps.txt"), "\n10.033 1 groundtruth/cubemaps/000000.exr\n"));
	CHECK(load_rig((folder / "rig.yaml").string()).ok);
	const RoomLoadResult room = load_room_file((folder / "room.yaml").string());
	CHECK_MESSAGE(room.ok, room.error);
	CHECK(contains(read_text(folder / "room.yaml"), "roomprobe_room: 1"));
}

// --------------------------------------------------------------------------------- raw frames

namespace {

FisheyeFrame make_colour_fisheye(double p_time_s) {
	FisheyeFrame frame;
	frame.timestamp_s = p_time_s;
	frame.image = cv::Mat(FISHEYE_SIZE, FISHEYE_SIZE, CV_8UC3);
	for (int y = 0; y < FISHEYE_SIZE; y++) {
		for (int x = 0; x < FISHEYE_SIZE; x++) {
			frame.image.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(x * 6), uchar(y * 6), uchar(200 - x - y));
		}
	}
	return frame;
}

} // namespace

TEST_CASE("raw frame recording: the writer's default; .zst frames play with the same frames as a PNG recording") {
	CHECK(RecordingWriteOptions().frame_format == FrameFormat::Zstd);
	const fs::path png = scratch_folder("same_frames_png");
	const fs::path zst = scratch_folder("same_frames_zstd");
	write_recording(png, 3, FrameFormat::Png);
	write_recording(zst, 3, FrameFormat::Zstd);

	// The files: raw frames for RGB, depth and the 8-bit fisheye; EXR for HDR and the ground truth.
	const std::string rgb = read_text(zst / "rgb.txt");
	CHECK(contains(rgb, "# RoomProbe recording: RGB images (8-bit R, G, B raw frames, zstd), RGB-D camera clock\n"));
	CHECK(contains(rgb, "\n10 rgb/000000.zst\n10.033 rgb/000001.zst\n"));
	CHECK(contains(read_text(zst / "depth.txt"), "\n10.07 depth/000002.zst\n"));
	CHECK(contains(read_text(zst / "fisheye.txt"), "\n9.99 fisheye/000000.zst\n10.05 fisheye/000001.exr\n"));
	CHECK(contains(read_text(zst / "groundtruth/cubemaps.txt"), "groundtruth/cubemaps/000000.exr"));
	CHECK(fs::exists(zst / "groundtruth/cubemaps/000000.png"));
	CHECK_FALSE(fs::exists(zst / "rgb/000000.png"));
	for (const auto &[file, type] : { std::pair<const char *, int>{ "rgb/000001.zst", CV_8UC3 }, std::pair<const char *, int>{ "depth/000001.zst", CV_16UC1 },
				 std::pair<const char *, int>{ "fisheye/000000.zst", CV_8UC1 } }) {
		CAPTURE(file);
		const std::string bytes = read_text(zst / file);
		RawFrameHeader header;
		REQUIRE(raw_frame_parse_header(reinterpret_cast<const uint8_t *>(bytes.data()), bytes.size(), &header) == "");
		CHECK(header.cv_type() == type);
		CHECK(header.width == (type == CV_8UC1 ? FISHEYE_SIZE : RGB_WIDTH));
		CHECK(header.data_bytes + kRawFrameHeaderBytes == bytes.size());
	}

	// The same frames, sample for sample (depth's NaN included), through the same reader.
	RecordingReader from_png;
	RecordingReader from_zst;
	REQUIRE(from_png.open(png.string()).ok);
	const RecordingStatus opened = from_zst.open(zst.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK_MESSAGE(from_zst.get_issues().empty(), all_issues(from_zst));
	REQUIRE(from_zst.rgbd_count() == 3);
	REQUIRE(from_png.rgbd_count() == 3);
	for (size_t i = 0; i < 3; i++) {
		CAPTURE(i);
		const RgbdFrameResult a = from_png.read_rgbd(i);
		const RgbdFrameResult b = from_zst.read_rgbd(i);
		REQUIRE_MESSAGE(b.ok, b.error);
		CHECK(same_samples(a.frame.rgb, b.frame.rgb));
		CHECK(same_samples(a.frame.depth_m, b.frame.depth_m));
		CHECK(b.frame.rgb.at<cv::Vec3b>(0, 1) == rgb_pattern(int(i), 1, 0)); // R, G, B
		CHECK(std::isnan(b.frame.depth_m.at<float>(0, 0)));
		CHECK(a.frame.timestamp_s == b.frame.timestamp_s);
		CHECK(a.frame.depth_timestamp_s == b.frame.depth_timestamp_s);
	}
	REQUIRE(from_zst.fisheye_count() == 2);
	for (size_t i = 0; i < 2; i++) {
		const FisheyeFrameResult a = from_png.read_fisheye(i);
		const FisheyeFrameResult b = from_zst.read_fisheye(i);
		REQUIRE_MESSAGE(b.ok, b.error);
		CHECK(a.frame.hdr == b.frame.hdr);
		CHECK(same_samples(a.frame.image, b.frame.image));
	}
	CHECK(from_zst.get_events().size() == from_png.get_events().size());

	// A colour fisheye frame keeps R, G, B in both formats.
	for (const FrameFormat format : { FrameFormat::Png, FrameFormat::Zstd }) {
		CAPTURE(frame_format_name(format));
		const fs::path folder = scratch_folder(std::string("colour_fisheye_") + frame_format_name(format));
		RecordingWriter writer;
		RecordingWriteOptions options;
		options.frame_format = format;
		REQUIRE(writer.open_without_room(folder.string(), make_rig(), options).ok);
		const FisheyeFrame colour = make_colour_fisheye(9.5);
		REQUIRE(writer.add_fisheye(colour).ok);
		REQUIRE(writer.close().ok);
		RecordingReader reader;
		REQUIRE(reader.open(folder.string()).ok);
		REQUIRE(reader.fisheye_count() == 1);
		const FisheyeFrameResult read = reader.read_fisheye(0);
		REQUIRE_MESSAGE(read.ok, read.error);
		CHECK_FALSE(read.frame.hdr);
		CHECK(same_samples(read.frame.image, colour.image));
	}

	// A zstd level the library does not have is refused at open, naming the option.
	RecordingWriter writer;
	RecordingWriteOptions bad_level;
	bad_level.zstd_level = 99;
	const RecordingStatus refused = writer.open(scratch_folder("bad_level").string(), make_rig(), make_room(), bad_level);
	CHECK_FALSE(refused.ok);
	CHECK(contains(refused.error, "zstd level 99"));
	CHECK(contains(refused.error, "zstd_level"));
}

TEST_CASE("raw frame recording: the reader goes by a file's first bytes, not its name") {
	const fs::path folder = scratch_folder("by_first_bytes");
	write_recording(folder, 3, FrameFormat::Zstd);
	// A raw frame named .png and a PNG named .zst both play.
	fs::rename(folder / "rgb/000000.zst", folder / "rgb/000000.png");
	replace_line(folder / "rgb.txt", 3, "10 rgb/000000.png");
	cv::Mat depth(RGB_HEIGHT, RGB_WIDTH, CV_16UC1, cv::Scalar(1234));
	REQUIRE(recording_io::write_png((folder / "depth/000001.zst").string(), depth) == "");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));
	check_plays_on(reader, 3, 2);
	const RgbdFrameResult first = reader.read_rgbd(0);
	REQUIRE_MESSAGE(first.ok, first.error);
	CHECK(first.frame.rgb.at<cv::Vec3b>(5, 7) == rgb_pattern(0, 7, 5));
	const RgbdFrameResult second = reader.read_rgbd(1);
	REQUIRE_MESSAGE(second.ok, second.error);
	CHECK(second.frame.depth_m.at<float>(5, 7) == doctest::Approx(1.234));
}

TEST_CASE("damaged raw frame recording: cut short, foreign, wrong type, wrong or absurd size are issues at open; corrupt data fails at read") {
	const fs::path folder = scratch_folder("damaged_zstd");
	write_recording(folder, 6, FrameFormat::Zstd);
	truncate_to_half(folder / "rgb/000000.zst");
	write_text(folder / "depth/000001.zst", "not a frame at all");
	REQUIRE(raw_frame_write((folder / "depth/000002.zst").string(), cv::Mat(RGB_HEIGHT, RGB_WIDTH, CV_8UC1, cv::Scalar(9))) == "");
	REQUIRE(raw_frame_write((folder / "rgb/000003.zst").string(), cv::Mat(60, 80, CV_8UC3, cv::Scalar(1, 2, 3))) == "");
	std::string absurd = read_text(folder / "rgb/000004.zst");
	absurd[18] = char(0x01); // width 64 + 65536: past the 32768-pixel side
	write_text(folder / "rgb/000004.zst", absurd);
	std::string longer = read_text(folder / "fisheye/000000.zst");
	write_text(folder / "fisheye/000000.zst", longer + "xyz");

	RecordingReader reader;
	const RecordingStatus opened = reader.open(folder.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	const struct {
		const char *file;
		const char *index;
		int line;
		const char *says;
	} expected[] = {
		{ "rgb/000000.zst", "rgb.txt", 3, "truncated: the raw frame ends at byte" },
		{ "depth/000001.zst", "depth.txt", 4, "neither a PNG nor a RoomProbe raw frame" },
		{ "depth/000002.zst", "depth.txt", 5, "a depth image must be 16-bit with 1 channel; this raw frame is 8-bit 1-channel" },
		{ "rgb/000003.zst", "rgb.txt", 6, "80x60 pixels, but the rig's RGB-D camera is 64x48" },
		{ "rgb/000004.zst", "rgb.txt", 7, "65600x48 pixels, more than RoomProbe reads" },
		{ "fisheye/000000.zst", "fisheye.txt", 3, "3 bytes after its zstd data" },
	};
	for (const auto &issue_expected : expected) {
		CAPTURE(issue_expected.file);
		const RecordingIssue *issue = find_issue(reader, std::string(issue_expected.file) + ": ");
		REQUIRE_MESSAGE(issue, all_issues(reader));
		CHECK(ends_with(issue->file, issue_expected.index));
		CHECK(issue->line == issue_expected.line);
		CHECK(contains(issue->message, issue_expected.says));
		CHECK(contains(issue->message, (folder / issue_expected.file).string()));
	}
	CHECK(reader.get_issues().size() == 6);
	check_plays_on(reader, 1, 1);

	// Files that go bad after open: corrupt data of the same length, then a file cut short.
	const std::string rgb_path = (folder / reader.get_rgbd_ref(0).rgb.path).string();
	std::string bytes = read_text(rgb_path);
	for (size_t i = kRawFrameHeaderBytes + 16; i < bytes.size() - 4; i += 5) {
		bytes[i] = char(bytes[i] ^ 0x33);
	}
	write_text(rgb_path, bytes);
	const RgbdFrameResult corrupt = reader.read_rgbd(0);
	CHECK_FALSE(corrupt.ok);
	CHECK(contains(corrupt.error, rgb_path + ": corrupt raw frame"));
	CHECK_FALSE(contains(corrupt.error, "truncated"));
	const std::string depth_path = (folder / reader.get_rgbd_ref(0).depth.path).string();
	write_text(rgb_path, read_text(folder / "rgb/000002.zst"));
	truncate_to_half(depth_path);
	const RgbdFrameResult cut = reader.read_rgbd(0);
	CHECK_FALSE(cut.ok);
	CHECK(contains(cut.error, depth_path + ": truncated"));
	// A raw frame whose zstd frame holds fewer samples than its header says: refused, not read past.
	std::string fewer = read_text(folder / "rgb/000002.zst");
	fewer[20] = char(RGB_HEIGHT + 1); // one row more than the data holds
	write_text(rgb_path, fewer);
	write_text(depth_path, read_text(folder / "depth/000005.zst"));
	const RgbdFrameResult mismatch = reader.read_rgbd(0);
	CHECK_FALSE(mismatch.ok);
	CHECK(contains(mismatch.error, rgb_path + ": corrupt raw frame: its zstd frame holds 9216 bytes, but 64x49 pixels"));
}

// ------------------------------------------------------------------------------- writer refusals

// Issue #38: two writers on one output. Each holds WRITING_MARKER, locked, while its recording is
// open: the second is refused (another process or this one), and their frames never mix.
TEST_CASE("recording writer: one writer a folder; a second at once is refused, and the frames never mix") {
	const fs::path folder = scratch_folder("two_writers");
	const fs::path marker = folder / recording_io::WRITING_MARKER;
	RecordingWriter first, second;
	REQUIRE(first.open(folder.string(), make_rig(), make_room()).ok);
	CHECK(fs::exists(marker));
	RecordingReader live;
	REQUIRE(live.open(folder.string()).ok);
	CHECK(contains(recording_test::all_issues(live), "a writer is adding to this recording now"));
	RecordingStatus refused = second.open(folder.string(), make_rig(), make_room());
	CHECK_FALSE(refused.ok);
	CHECK(contains(refused.error, folder.string() + ": another writer is recording into this folder now"));
	RecordingWriteOptions into_used;
	into_used.allow_non_empty_folder = true; // not even when told it may write into a used folder
	refused = second.open(folder.string(), make_rig(), make_room(), into_used);
	CHECK(contains(refused.error, "another writer is recording into this folder now"));
	CHECK(fs::exists(marker)); // the first's, kept
	for (int i = 0; i < 3; i++) {
		REQUIRE(first.add_rgbd(make_rgbd(i)).ok);
	}
	REQUIRE(first.close().ok);
	CHECK_FALSE(fs::exists(marker)); // closed: no marker left

	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK(reader.rgbd_count() == 3);
	CHECK_FALSE(contains(recording_test::all_issues(reader), "writer"));
	// Afterwards the folder is a recording: the second is refused as ever, and leaves no marker.
	refused = second.open(folder.string(), make_rig(), make_room());
	CHECK(contains(refused.error, "the folder is not empty"));
	CHECK_FALSE(fs::exists(marker));
}

// Issue #38: SIGKILL of synth midway, then the partial recording played. What a killed writer
// leaves: its marker, no longer locked, and nothing of what it writes on closing (the ground-truth
// trajectories). tests/host/test_paths.sh kills a real synth; this stands in for one here.
TEST_CASE("recording never closed (its writer killed midway): the frames its indexes list play, and every reader says why the rest is missing") {
	const fs::path folder = scratch_folder("abandoned");
	{
		RecordingWriter writer;
		REQUIRE(writer.open(folder.string(), make_rig(), make_room()).ok);
		for (int i = 0; i < 3; i++) {
			REQUIRE(writer.add_rgbd(make_rgbd(i)).ok);
			REQUIRE(writer.add_ground_truth_pose(RecordingStream::Rgbd, rgb_time(i), Pose()).ok);
		}
		REQUIRE(writer.close().ok);
	}
	fs::remove_all(folder / "groundtruth");
	write_text(folder / recording_io::WRITING_MARKER, "pid 1\n");

	RecordingReader reader;
	const RecordingStatus opened = reader.open(folder.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK(contains(recording_test::all_issues(reader), "the recording was never closed"));
	REQUIRE(reader.rgbd_count() == 3);
	for (size_t i = 0; i < 3; i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		CHECK_MESSAGE(frame.ok, frame.error);
	}
	CHECK_FALSE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	// The evaluation refuses, saying why by itself (with --quiet no recording issue is shown).
	EvaluationOptions options;
	options.recording = folder.string();
	const EvaluationResult evaluated = evaluate_recording(options);
	CHECK_FALSE(evaluated.ok);
	CHECK(contains(evaluated.error, "no ground-truth RGB-D trajectory"));
	CHECK(contains(evaluated.error, "the recording was never closed"));
	// A new writer takes the folder only when told it may write into a used one, and leaves no marker.
	RecordingWriter again;
	CHECK(contains(again.open(folder.string(), make_rig(), make_room()).error, "the folder is not empty"));
	RecordingWriteOptions into_used;
	into_used.allow_non_empty_folder = true;
	REQUIRE(again.open(folder.string(), make_rig(), make_room(), into_used).ok);
	REQUIRE(again.close().ok);
	CHECK_FALSE(fs::exists(folder / recording_io::WRITING_MARKER));
}

TEST_CASE("recording writer refuses a non-empty folder and overwrites nothing") {
	const fs::path folder = scratch_folder("non_empty");
	fs::create_directories(folder);
	write_text(folder / "rgb.txt", "user data");
	RecordingWriter writer;
	const RecordingStatus refused = writer.open(folder.string(), make_rig(), make_room());
	CHECK_FALSE(refused.ok);
	CHECK(contains(refused.error, folder.string()));
	CHECK(contains(refused.error, "not empty"));
	CHECK_FALSE(writer.is_open());
	CHECK(read_text(folder / "rgb.txt") == "user data");
	CHECK_FALSE(fs::exists(folder / "rig.yaml"));

	// Told to, it writes into the folder; a previous recording's ground truth does not survive.
	fs::create_directories(folder / "groundtruth");
	write_text(folder / "groundtruth/rgb_trajectory.txt", "1 0 0 0 0 0 0 1\n");
	write_text(folder / "notes.txt", "more user data");
	RecordingWriteOptions options;
	options.allow_non_empty_folder = true;
	const RecordingStatus allowed = writer.open(folder.string(), make_rig(), make_room(), options);
	CHECK_MESSAGE(allowed.ok, allowed.error);
	CHECK(writer.close().ok);
	CHECK(fs::exists(folder / "rig.yaml"));
	CHECK(read_text(folder / "notes.txt") == "more user data");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_FALSE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	CHECK(reader.rgbd_count() == 0);

	// A file where the folder should be.
	const fs::path file = scratch_folder("a_file");
	write_text(file, "x");
	const RecordingStatus not_folder = writer.open(file.string(), make_rig(), make_room());
	CHECK_FALSE(not_folder.ok);
	CHECK(contains(not_folder.error, "not a folder"));
}

TEST_CASE("recording writer rejects bad frames with errors naming the file, and writes no index line") {
	const fs::path folder = scratch_folder("writer_errors");
	RecordingWriter writer;
	REQUIRE(writer.open(folder.string(), make_rig(), make_room()).ok);
	REQUIRE(writer.add_rgbd(make_rgbd(0)).ok);

	RgbdFrame small = make_rgbd(1);
	cv::resize(small.rgb, small.rgb, cv::Size(32, 24));
	RecordingStatus status = writer.add_rgbd(small);
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "rgb/000001.zst")); // raw frames: the default
	CHECK(contains(status.error, "32x24"));

	RgbdFrame backwards = make_rgbd(1);
	backwards.timestamp_s = 9.0;
	backwards.depth_timestamp_s = 9.0;
	status = writer.add_rgbd(backwards);
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "rgb.txt"));
	CHECK(contains(status.error, "not after"));

	RgbdFrame too_far = make_rgbd(1);
	too_far.depth_m.at<float>(1, 1) = 70.0f; // 70000 mm does not fit 16 bits
	status = writer.add_rgbd(too_far);
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "depth/000001.zst"));

	FisheyeFrame mislabelled = make_gray_fisheye();
	mislabelled.hdr = true;
	status = writer.add_fisheye(mislabelled);
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "fisheye/000000"));

	CubemapFaces faces;
	for (cv::Mat &face : faces) {
		face = cv::Mat(4, 4, CV_32FC3, cv::Scalar(1, 1, 1));
	}
	status = writer.add_ground_truth_cubemap(10.0, 7, faces);
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "cubemaps.txt"));
	CHECK(contains(status.error, "probe index 7"));

	status = writer.add_ground_truth_pose(RecordingStream::Rgbd, 10.0, gt_rgb_pose(0));
	CHECK(status.ok);
	status = writer.add_ground_truth_pose(RecordingStream::Rgbd, 10.0, gt_rgb_pose(1));
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "rgb_trajectory.txt"));

	REQUIRE(writer.add_rgbd(make_rgbd(1)).ok); // the failed calls used no frame number
	REQUIRE(writer.close().ok);
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));
	check_plays_on(reader, 2, 0);
	CHECK(reader.get_rgbd_ref(1).rgb.path == "rgb/000001.zst");
}

// ----------------------------------------------------------------------------- damaged recordings

TEST_CASE("damaged recording: a missing PNG is an issue with file and line, the rest plays") {
	const fs::path folder = scratch_folder("missing_png");
	write_recording(folder, 4);
	fs::remove(folder / "rgb/000001.png");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *issue = find_issue(reader, "rgb/000001.png");
	REQUIRE_MESSAGE(issue, all_issues(reader));
	CHECK(ends_with(issue->file, "rgb.txt"));
	CHECK(issue->line == 4); // two header lines, then frames 0, 1, ...
	CHECK(contains(issue->message, "missing"));
	CHECK(reader.get_issues().size() == 1);
	check_plays_on(reader, 3, 2);
	CHECK(reader.get_rgbd_ref(1).rgb.timestamp_s == rgb_time(2));
}

TEST_CASE("damaged recording: a truncated PNG is caught at open and at read") {
	const fs::path folder = scratch_folder("truncated_png");
	write_recording(folder, 4);
	truncate_to_half(folder / "depth/000002.png");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *issue = find_issue(reader, "depth/000002.png");
	REQUIRE_MESSAGE(issue, all_issues(reader));
	CHECK(ends_with(issue->file, "depth.txt"));
	CHECK(issue->line == 5);
	CHECK(contains(issue->message, "truncated"));
	check_plays_on(reader, 3, 2);

	// A file that goes bad after open: read_rgbd fails naming it; the other frames still read.
	truncate_to_half(folder / "rgb/000001.png");
	const RgbdFrameResult broken = reader.read_rgbd(1);
	CHECK_FALSE(broken.ok);
	CHECK(contains(broken.error, "rgb/000001.png"));
	CHECK(contains(broken.error, "truncated"));
	CHECK(reader.read_rgbd(0).ok);
	CHECK(reader.read_rgbd(2).ok);
}

TEST_CASE("damaged recording: a PNG with corrupt data fails to read, naming the file") {
	const fs::path folder = scratch_folder("corrupt_png");
	write_recording(folder, 3);
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	// Same length, chunks intact, but the compressed data overwritten (its CRC no longer holds).
	const fs::path png = folder / "rgb/000000.png";
	std::string bytes = read_text(png);
	const size_t data = bytes.find("IDAT");
	REQUIRE(data != std::string::npos);
	for (size_t i = data + 8; i < data + 40 && i < bytes.size() - 12; i++) {
		bytes[i] = char(0x55);
	}
	write_text(png, bytes);
	const RgbdFrameResult broken = reader.read_rgbd(0);
	CHECK_FALSE(broken.ok);
	CHECK(contains(broken.error, "rgb/000000.png"));
	CHECK_FALSE(contains(broken.error, "truncated")); // the file is whole: corrupt, not cut short
	CHECK(reader.read_rgbd(1).ok);

	// A damaged chunk length is corruption too, not a file cut short.
	const fs::path png1 = folder / "rgb/000001.png";
	std::string bytes1 = read_text(png1);
	const size_t idat1 = bytes1.find("IDAT");
	REQUIRE(idat1 != std::string::npos);
	bytes1[idat1 - 4] = char(0xF0);
	write_text(png1, bytes1);
	const RgbdFrameResult bad_length = reader.read_rgbd(1);
	CHECK_FALSE(bad_length.ok);
	CHECK(contains(bad_length.error, "rgb/000001.png: corrupt PNG: chunk 'IDAT'"));
	CHECK(contains(bad_length.error, "above PNG's limit"));

	fs::remove(folder / "fisheye/000001.exr");
	const FisheyeFrameResult missing = reader.read_fisheye(1);
	CHECK_FALSE(missing.ok);
	CHECK(contains(missing.error, "fisheye/000001.exr"));
	CHECK(contains(missing.error, "missing"));
	CHECK(reader.read_fisheye(0).ok);
}

TEST_CASE("damaged recording: 65535 depth is no reading, never 65.5 m; an HDR frame with NaN or infinity fails to read, naming the file") {
	const fs::path folder = scratch_folder("impossible_values");
	write_recording(folder, 3);
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	// All 65535 (a saturated sensor's "none", once fused as a wall 65.5 m away): no reading at all,
	// which tracking then reports (a frame with no depth is lost: test_slam_dense.cpp). The RGB
	// image stays usable (a calibration recording has boards without depth).
	const std::string depth_path = (folder / reader.get_rgbd_ref(1).depth.path).string();
	REQUIRE(recording_io::write_png(depth_path, cv::Mat(RGB_HEIGHT, RGB_WIDTH, CV_16UC1, cv::Scalar(65535))) == "");
	const RgbdFrameResult saturated = reader.read_rgbd(1);
	REQUIRE_MESSAGE(saturated.ok, saturated.error);
	CHECK(cv::countNonZero(saturated.frame.depth_m == saturated.frame.depth_m) == 0); // NaN everywhere
	// One 65535 pixel among readings is simply no reading there.
	cv::Mat raw(RGB_HEIGHT, RGB_WIDTH, CV_16UC1, cv::Scalar(1500));
	raw.at<uint16_t>(3, 4) = 65535;
	REQUIRE(recording_io::write_png(depth_path, raw) == "");
	const RgbdFrameResult mostly = reader.read_rgbd(1);
	REQUIRE_MESSAGE(mostly.ok, mostly.error);
	CHECK(std::isnan(mostly.frame.depth_m.at<float>(3, 4)));
	CHECK(mostly.frame.depth_m.at<float>(3, 5) == doctest::Approx(1.5));
	// The HDR fisheye frame with a NaN and an infinity: refused, never scored as a perfect map.
	size_t hdr = reader.fisheye_count();
	for (size_t i = 0; i < reader.fisheye_count(); i++) {
		hdr = ends_with(reader.get_fisheye_ref(i).path, ".exr") ? i : hdr;
	}
	REQUIRE(hdr < reader.fisheye_count());
	const std::string exr_path = (folder / reader.get_fisheye_ref(hdr).path).string();
	{
		// Written with OpenEXR itself: RoomProbe's writer refuses non-finite values.
		std::vector<Imf::Rgba> pixels(size_t(FISHEYE_SIZE) * FISHEYE_SIZE, Imf::Rgba(0.5f, 0.5f, 0.5f, 1.0f));
		pixels[size_t(10) * FISHEYE_SIZE + 10].g = std::numeric_limits<float>::quiet_NaN();
		pixels[size_t(10) * FISHEYE_SIZE + 11].r = std::numeric_limits<float>::infinity();
		Imf::RgbaOutputFile file(exr_path.c_str(), FISHEYE_SIZE, FISHEYE_SIZE, Imf::WRITE_RGBA);
		file.setFrameBuffer(pixels.data(), 1, size_t(FISHEYE_SIZE));
		file.writePixels(FISHEYE_SIZE);
	}
	const FisheyeFrameResult bad = reader.read_fisheye(hdr);
	CHECK_FALSE(bad.ok);
	CHECK(contains(bad.error, exr_path + ": 2 channel values are NaN or infinite"));
	// RoomProbe's writer refuses to write such a frame at all.
	{
		RecordingWriter writer;
		fs::remove_all(folder.string() + "_writer");
		REQUIRE(writer.open((folder.string() + "_writer"), make_rig(), make_room()).ok);
		FisheyeFrame nan_frame = make_hdr_fisheye();
		nan_frame.image.at<cv::Vec3f>(3, 3)[1] = std::numeric_limits<float>::quiet_NaN();
		const RecordingStatus refused = writer.add_fisheye(nan_frame);
		CHECK_FALSE(refused.ok);
		CHECK(contains(refused.error, "1 of its 4800 HDR values are NaN or infinite"));
		fs::remove_all(folder.string() + "_writer");
	}
	// An EXR whose header claims a huge image (a damaged or hostile file): refused before any
	// pixel is allocated (100000 x 100000 floats would be 120 GB).
	{
		Imf::Header header(100000, 100000);
		header.channels().insert("R", Imf::Channel(Imf::FLOAT));
		header.channels().insert("G", Imf::Channel(Imf::FLOAT));
		header.channels().insert("B", Imf::Channel(Imf::FLOAT));
		Imf::OutputFile file(exr_path.c_str(), header); // no pixels written: only the header matters
	}
	const FisheyeFrameResult huge = reader.read_fisheye(hdr);
	CHECK_FALSE(huge.ok);
	CHECK(contains(huge.error, exr_path + ": "));
	CHECK(contains(huge.error, "100000 x 100000"));
}

TEST_CASE("damaged recording: a timestamp going backwards in rgb.txt skips that frame") {
	const fs::path folder = scratch_folder("backwards");
	write_recording(folder, 4);
	replace_line(folder / "rgb.txt", 5, "9.5 rgb/000002.png");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *issue = find_issue(reader, "goes backwards");
	REQUIRE_MESSAGE(issue, all_issues(reader));
	CHECK(ends_with(issue->file, "rgb.txt"));
	CHECK(issue->line == 5);
	CHECK(contains(issue->message, "9.5"));
	CHECK(contains(issue->message, "rgb/000002.png"));
	// Its depth frame is left without a partner: a second issue, at depth.txt line 5.
	const RecordingIssue *unpaired = find_issue(reader, "no RGB frame");
	REQUIRE_MESSAGE(unpaired, all_issues(reader));
	CHECK(ends_with(unpaired->file, "depth.txt"));
	CHECK(unpaired->line == 5);
	check_plays_on(reader, 3, 2);
	CHECK(reader.get_rgbd_ref(2).rgb.timestamp_s == rgb_time(3));
}

TEST_CASE("damaged recording: an RGB image of the wrong size is an issue naming its size") {
	const fs::path folder = scratch_folder("wrong_size");
	write_recording(folder, 4);
	REQUIRE(cv::imwrite((folder / "rgb/000000.png").string(), cv::Mat(60, 80, CV_8UC3, cv::Scalar(1, 2, 3))));
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *issue = find_issue(reader, "rgb/000000.png");
	REQUIRE_MESSAGE(issue, all_issues(reader));
	CHECK(ends_with(issue->file, "rgb.txt"));
	CHECK(issue->line == 3);
	CHECK(contains(issue->message, "80x60"));
	CHECK(contains(issue->message, "64x48"));
	check_plays_on(reader, 3, 2);
}

TEST_CASE("damaged recording: an 8-bit depth PNG is an issue") {
	const fs::path folder = scratch_folder("depth_8bit");
	write_recording(folder, 4);
	REQUIRE(cv::imwrite((folder / "depth/000003.png").string(), cv::Mat(RGB_HEIGHT, RGB_WIDTH, CV_8UC1, cv::Scalar(9))));
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *issue = find_issue(reader, "depth/000003.png");
	REQUIRE_MESSAGE(issue, all_issues(reader));
	CHECK(ends_with(issue->file, "depth.txt"));
	CHECK(issue->line == 6);
	CHECK(contains(issue->message, "16-bit"));
	CHECK(contains(issue->message, "8-bit"));
	check_plays_on(reader, 3, 2);
}

TEST_CASE("damaged recording: bad index lines and a missing fisheye image are issues") {
	const fs::path folder = scratch_folder("bad_lines");
	write_recording(folder, 3);
	std::string fisheye = read_text(folder / "fisheye.txt");
	write_text(folder / "fisheye.txt", fisheye + "not-a-time fisheye/000009.png\n10.2\n10.3 ../../etc/passwd\n10.4 fisheye/../../outside.png\n10.5 /etc/passwd\n");
	fs::remove(folder / "fisheye/000000.png");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *missing = find_issue(reader, "fisheye/000000.png");
	REQUIRE_MESSAGE(missing, all_issues(reader));
	CHECK(missing->line == 3);
	const RecordingIssue *not_time = find_issue(reader, "not-a-time");
	REQUIRE_MESSAGE(not_time, all_issues(reader));
	CHECK(not_time->line == 5);
	const RecordingIssue *no_path = find_issue(reader, "expected 'timestamp_s relative/path'");
	REQUIRE_MESSAGE(no_path, all_issues(reader));
	CHECK(no_path->line == 6);
	// No index may reach outside the recording (the reader once opened /etc/passwd this way).
	for (const auto &[text, line] : { std::pair<const char *, int>{ "'../../etc/passwd' leaves the recording folder", 7 },
			 std::pair<const char *, int>{ "'fisheye/../../outside.png' leaves the recording folder", 8 },
			 std::pair<const char *, int>{ "'/etc/passwd' is an absolute path", 9 } }) {
		const RecordingIssue *escape = find_issue(reader, text);
		REQUIRE_MESSAGE(escape, all_issues(reader));
		CHECK(escape->line == line);
	}
	check_plays_on(reader, 3, 1);
}

TEST_CASE("damaged recording: impossible exposures and gains in capture.txt are issues, and the frames play") {
	// Issue #38: zero or negative exposures and absurd gains were used.
	const fs::path folder = scratch_folder("capture_bad");
	write_recording(folder, 3);
	std::istringstream rgb(read_text(folder / "rgb.txt"));
	std::string line, stamp;
	while (std::getline(rgb, line) && (line.empty() || line[0] == '#')) {
	}
	stamp = line.substr(0, line.find(' '));
	write_text(folder / "capture.txt", "rgbd " + stamp + " 1.0 7 0 2.0\nrgbd " + stamp + " 1.0 7 -5 2.0\nrgbd " + stamp + " 1.0 7 5000 1e30\nrgbd " + stamp +
			" 1.0 7 5000 nan\n");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_MESSAGE(find_issue(reader, "exposure_us 0 is not in (0, 10000000]"), all_issues(reader));
	CHECK_MESSAGE(find_issue(reader, "exposure_us -5 is not in (0, 10000000]"), all_issues(reader));
	CHECK_MESSAGE(find_issue(reader, "gain 1e30 is not in [0, 1000]"), all_issues(reader));
	check_plays_on(reader, 3, 2);
}

TEST_CASE("damaged recording: timestamps in milliseconds are an issue that says so, and the frames play as stamped") {
	// Issue #38: live playback ran 1000 times slower without a word.
	const fs::path folder = scratch_folder("milliseconds");
	write_recording(folder, 4);
	for (const char *index : { "rgb.txt", "depth.txt" }) {
		std::istringstream in(read_text(folder / index));
		std::string line, out;
		while (std::getline(in, line)) {
			if (!line.empty() && line[0] != '#') {
				const size_t space = line.find(' ');
				line = std::to_string(std::stod(line.substr(0, space)) * 1000.0) + line.substr(space);
			}
			out += line + "\n";
		}
		write_text(folder / index, out);
	}
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_MESSAGE(find_issue(reader, "s apart (median): timestamps must be in seconds"), all_issues(reader));
	CHECK(reader.rgbd_count() >= 3); // frame 2's depth, 4 ms after its colour, is now 4 s after it
	const fs::path seconds = scratch_folder("seconds");
	write_recording(seconds, 4);
	RecordingReader plain;
	REQUIRE(plain.open(seconds.string()).ok);
	CHECK_FALSE(find_issue(plain, "timestamps must be in seconds"));
}

TEST_CASE("damaged recording: a ground-truth cubemap path out of the recording is an issue, and nothing outside is opened") {
	// Issue #38: groundtruth/cubemaps.txt's paths were followed out of the recording.
	const fs::path folder = scratch_folder("cubemap_escape");
	write_recording(folder);
	const std::string index = read_text(folder / "groundtruth/cubemaps.txt");
	write_text(folder / "groundtruth/cubemaps.txt", index + "10.5 1 ../../outside.exr\n10.6 1 groundtruth/../../x.exr\n");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK_MESSAGE(find_issue(reader, "'../../outside.exr' leaves the recording folder; paths stay inside it; cubemap skipped"), all_issues(reader));
	CHECK_MESSAGE(find_issue(reader, "'groundtruth/../../x.exr' leaves the recording folder"), all_issues(reader));
	CHECK(reader.ground_truth_cubemap_count() == 1);
}

TEST_CASE("damaged recording: malformed room.yaml fails open, naming the file and field") {
	const fs::path folder = scratch_folder("bad_room");
	write_recording(folder, 3);
	RecordingReader reader;

	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m: [ [0, 0], [4, 0\n");
	RecordingStatus status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml"));
	CHECK(contains(status.error, "malformed YAML"));
	CHECK_FALSE(reader.is_open());

	// Found by fuzzing (./roomprobe fuzz room): OpenCV's YAML parser never returned on it.
	write_text(folder / "room.yaml", "%YAML:1.0\n---J#  RoomProom: 1.\n(  - [ 0., 0. ]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: malformed YAML: line 2: text after the document marker"));

	// Found by fuzzing: a field indented under a comment, then fields at column 0 (and a comment
	// of bytes that are not UTF-8) hung OpenCV's parser too.
	write_text(folder / "room.yaml", "%YAML:1.0\n---\n#  c\n   translation_m: [ 3.78, 1.54,\n       1.12 ]\nm:\n   - [ 1., 0. ]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: malformed YAML: line 4: the first field is indented"));
	write_text(folder / "room.yaml", "%YAML:1.0\n---\n# \xff\xff\xff\nroomprobe_room: 1\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: malformed YAML: line 3: a comment that is not UTF-8 text"));

	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m: [ [0, 0], [4, 0, 1], [4, 5] ]\nceiling_height_m: 2.5\n"
									 "initial_rgb_pose:\n  rotation_xyzw: [0, 0, 0, 1]\n  translation_m: [0, 1.5, 0]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: floorplan_m[1]: must be a list of 2 numbers"));

	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m: [ [0, 0], [4, 0], [4, 5] ]\n"
									 "initial_rgb_pose:\n  rotation_xyzw: [0, 0, 0, 1]\n  translation_m: [0, 1.5, 0]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: ceiling_height_m: missing"));

	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m: [ [0, 0], [4, 5], [4, 0], [0, 5] ]\nceiling_height_m: 2.5\n"
									 "initial_rgb_pose:\n  rotation_xyzw: [0, 0, 0, 1]\n  translation_m: [0, 1.5, 0]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: floorplan_m: "));

	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m: [ [0, 0], [4, 0], [4, 5] ]\nceiling_height_m: 2.5\n"
									 "initial_rgb_pose:\n  rotation_xyzw: [0, 0, 0, 1]\n  translation_m: [0, 1.5, 0]\nprobe: [ [1, 1, 1] ]\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: probe: unknown field"));

	// A list at its key's own indentation is YAML, but cv::FileStorage refuses it: said plainly.
	write_text(folder / "room.yaml", "%YAML:1.0\n---\nroomprobe_room: 1\nfloorplan_m:\n- [0, 0]\n- [4, 0]\n- [4, 5]\nceiling_height_m: 2.5\n");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "room.yaml: malformed YAML: line 5: a list item must be indented under its key"));
	// Indented lists, nested maps and comments in UTF-8 pass the layout check.
	write_text(folder / "room.yaml", "%YAML:1.0\n---\n# a comment in UTF-8: \xc3\xbc\nroomprobe_room: 1\nfloorplan_m:\n  - [0, 0]\n  - [4, 0]\n  - [4, 5]\n"
									 "ceiling_height_m: 2.5\ninitial_rgb_pose:\n  rotation_xyzw: [0, 0, 0, 1]\n  translation_m: [0, 1.5, 0]\n"
									 "probes:\n  - [1, 1, 1]\n");
	status = reader.open(folder.string());
	CHECK_MESSAGE(status.ok, status.error);
	CHECK(reader.get_room().floorplan.points.size() == 3);

	// Without room.yaml the recording has no room (SLAM only), and its cubemaps are an issue.
	fs::remove(folder / "room.yaml");
	status = reader.open(folder.string());
	REQUIRE_MESSAGE(status.ok, status.error);
	CHECK_FALSE(reader.has_room());
	CHECK(reader.ground_truth_cubemap_count() == 0);
	const RecordingIssue *cubemaps = find_issue(reader, "no ground-truth cubemaps");
	REQUIRE(cubemaps != nullptr);
	CHECK(contains(cubemaps->file, "cubemaps.txt"));
	check_plays_on(reader, 3, 2);
}

TEST_CASE("damaged recording: a missing rig.yaml or index fails open, naming the file") {
	const fs::path folder = scratch_folder("no_rig");
	write_recording(folder, 3);
	RecordingReader reader;
	fs::remove(folder / "depth.txt");
	RecordingStatus status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "depth.txt"));
	CHECK(contains(status.error, "missing"));

	fs::remove(folder / "rig.yaml");
	status = reader.open(folder.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, (folder / "rig.yaml").string()));

	status = reader.open((folder / "nowhere").string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "no such recording folder"));

	// A folder where an index should be is said to be one, not "missing".
	const fs::path other = scratch_folder("index_is_folder");
	write_recording(other, 3);
	fs::remove(other / "rgb.txt");
	fs::create_directory(other / "rgb.txt");
	status = reader.open(other.string());
	CHECK_FALSE(status.ok);
	CHECK(contains(status.error, "rgb.txt: a folder, not a file"));
}

TEST_CASE("damaged recording: broken ground truth is an issue, not a failure") {
	const fs::path folder = scratch_folder("bad_groundtruth");
	write_recording(folder, 3);
	write_text(folder / "groundtruth/fisheye_trajectory.txt", "# t tx ty tz qx qy qz qw\n9.99 0 0 0 0 0 0 1\n10.05 0 0 zero 0 0 0 1\n");
	write_text(folder / "groundtruth/cubemaps.txt", "# t probe path\n10.0 5 groundtruth/cubemaps/000000.exr\n10.1 0 groundtruth/cubemaps/000099.exr\n");
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	CHECK(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	CHECK_FALSE(reader.has_ground_truth_trajectory(RecordingStream::Fisheye));
	bool trajectory_issue = false;
	for (const RecordingIssue &issue : reader.get_issues()) {
		if (ends_with(issue.file, "fisheye_trajectory.txt")) {
			trajectory_issue = true;
			CHECK(issue.line == 3);
		}
	}
	CHECK_MESSAGE(trajectory_issue, all_issues(reader));
	const RecordingIssue *probe = find_issue(reader, "probe index '5'");
	REQUIRE_MESSAGE(probe, all_issues(reader));
	CHECK(probe->line == 2);
	const RecordingIssue *missing = find_issue(reader, "000099.exr");
	REQUIRE_MESSAGE(missing, all_issues(reader));
	CHECK(missing->line == 3);
	CHECK(reader.ground_truth_cubemap_count() == 0);
	check_plays_on(reader, 3, 2);
}

// ------------------------------------------------------------------------------------ SLAM only

TEST_CASE("SLAM-only recording: no room and a rig without a fisheye write and read back") {
	const fs::path folder = scratch_folder("slam_only");
	Rig rig = make_rig();
	rig.fisheye = OmniParams(); // an RGB-D camera alone
	RecordingWriter writer;
	const RecordingStatus opened = writer.open_without_room(folder.string(), rig);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	for (int i = 0; i < 3; i++) {
		const RecordingStatus added = writer.add_rgbd(make_rgbd(i));
		CHECK_MESSAGE(added.ok, added.error);
		CHECK(writer.add_ground_truth_pose(RecordingStream::Rgbd, rgb_time(i), gt_rgb_pose(i)).ok);
	}
	const RecordingStatus fisheye = writer.add_fisheye(make_gray_fisheye());
	CHECK_FALSE(fisheye.ok);
	CHECK(contains(fisheye.error, "the rig has no fisheye"));
	CubemapFaces faces;
	for (cv::Mat &face : faces) {
		face = cv::Mat(CUBE_SIZE, CUBE_SIZE, CV_32FC3, cv::Scalar::all(1.0));
	}
	const RecordingStatus cube = writer.add_ground_truth_cubemap(10.0, 0, faces);
	CHECK_FALSE(cube.ok);
	CHECK(contains(cube.error, "has no room"));
	REQUIRE(writer.close().ok);
	CHECK_FALSE(fs::exists(folder / "room.yaml"));
	CHECK_FALSE(fs::exists(folder / "fisheye.txt"));
	CHECK_FALSE(fs::exists(folder / "fisheye"));

	RecordingReader reader;
	const RecordingStatus status = reader.open(folder.string());
	REQUIRE_MESSAGE(status.ok, status.error);
	CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));
	CHECK_FALSE(reader.has_room());
	CHECK_FALSE(reader.get_rig().has_fisheye());
	check_plays_on(reader, 3, 0);
	const RgbdFrameResult frame = reader.read_rgbd(1);
	REQUIRE_MESSAGE(frame.ok, frame.error);
	CHECK(frame.frame.rgb.at<cv::Vec3b>(7, 9) == rgb_pattern(1, 9, 7));
	CHECK(frame.frame.depth_m.at<float>(7, 9) == doctest::Approx(depth_units(1, 9, 7) * 0.001));
	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	CHECK(reader.ground_truth_trajectory(RecordingStream::Rgbd).size() == 3);

	// A stray fisheye.txt beside a rig without a fisheye: its frames are an issue, left out.
	write_text(folder / "fisheye.txt", "9.99 fisheye/000000.png\n");
	REQUIRE(reader.open(folder.string()).ok);
	const RecordingIssue *stray = find_issue(reader, "has no fisheye");
	REQUIRE(stray != nullptr);
	CHECK(contains(stray->file, "fisheye.txt"));
	CHECK(reader.fisheye_count() == 0);
}

TEST_CASE("SLAM-only recording: a rig with a fisheye, but no fisheye frames and no room") {
	const fs::path folder = scratch_folder("no_room_no_fisheye_frames");
	RecordingWriter writer;
	REQUIRE(writer.open_without_room(folder.string(), make_rig()).ok);
	for (int i = 0; i < 2; i++) {
		CHECK(writer.add_rgbd(make_rgbd(i)).ok);
	}
	REQUIRE(writer.close().ok);
	CHECK(fs::exists(folder / "fisheye.txt")); // the rig has a fisheye: its index, empty

	RecordingReader reader;
	const RecordingStatus status = reader.open(folder.string());
	REQUIRE_MESSAGE(status.ok, status.error);
	CHECK(reader.get_issues().empty());
	CHECK_FALSE(reader.has_room());
	CHECK(reader.get_rig().has_fisheye());
	check_plays_on(reader, 2, 0);

	// The fisheye's index stays required while the rig has a fisheye.
	fs::remove(folder / "fisheye.txt");
	const RecordingStatus missing = reader.open(folder.string());
	CHECK_FALSE(missing.ok);
	CHECK(contains(missing.error, "fisheye.txt: missing"));

	// A new recording written into this folder without a room drops the old room.yaml.
	const fs::path reused = scratch_folder("room_then_none");
	write_recording(reused, 1);
	RecordingWriteOptions options;
	options.allow_non_empty_folder = true;
	REQUIRE(writer.open_without_room(reused.string(), make_rig(), options).ok);
	REQUIRE(writer.close().ok);
	REQUIRE(reader.open(reused.string()).ok);
	CHECK_FALSE(reader.has_room());
}

TEST_CASE("recording issues: issue_lines lists each once, in the order met (what eval and bench print)") {
	const std::vector<RecordingIssue> issues = { { "rgb.txt", 3, "a" }, { "rgb.txt", 3, "a" }, { "depth.txt", 0, "b" }, { "rgb.txt", 4, "a" } };
	CHECK(issue_lines(issues) == std::vector<std::string>{ "rgb.txt:3: a", "depth.txt: b", "rgb.txt:4: a" });
}
