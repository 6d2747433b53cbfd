// The 7-Scenes-layout reader (recording/frames_dataset.h) on small folders written here, with the
// real dataset's file names and formats (colour JPEG, 16-bit millimetre depth PNG, 4x4 pose text,
// 3x3 K), and on the real 400 frames in ../shared/data/rgbd-7scenes when they are there.

#include "recording/frames_dataset.h"

#include "recording_test_issues.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace roomprobe;
namespace fs = std::filesystem;

using recording_test::all_issues;

namespace {

constexpr int WIDTH = 64;
constexpr int HEIGHT = 48;

const std::string REAL_FOLDER = std::string(ROOMPROBE_SHARED_DATA) + "/rgbd-7scenes";

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

void write_text(const fs::path &p_path, const std::string &p_text) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file << p_text;
}

std::string read_text(const fs::path &p_path) {
	std::ifstream file(p_path, std::ios::binary);
	std::stringstream text;
	text << file.rdbuf();
	return text.str();
}

std::string name(int p_frame, const char *p_kind) {
	char text[64];
	std::snprintf(text, sizeof(text), "frame-%06d.%s", p_frame, p_kind);
	return text;
}

// The true pose of frame N: turning about y and moving along x.
Pose true_pose(int p_frame) {
	Pose pose;
	pose.rotation = glm::angleAxis(0.05 * p_frame, glm::dvec3(0.0, 1.0, 0.0));
	pose.translation = glm::dvec3(0.01 * p_frame, -0.2, 0.3);
	return pose;
}

// As 7-Scenes writes them: the 4x4 matrix row by row, %.18e.
std::string pose_text(const Pose &p_pose) {
	const glm::dmat4 m = pose_to_matrix(p_pose);
	std::string text;
	for (int row = 0; row < 4; row++) {
		for (int col = 0; col < 4; col++) {
			char number[40];
			std::snprintf(number, sizeof(number), "%.18e", m[col][row]);
			text += std::string(col ? " " : "") + number;
		}
		text += "\n";
	}
	return text;
}

// Frame N: colour a flat (R, G, B) = (40 N, 120, 200) (JPEG keeps flat colours within a few
// levels), depth 1000 + 10 N mm with no reading at (0, 0).
void write_frame(const fs::path &p_folder, int p_frame, bool p_pose = true) {
	const cv::Mat bgr(HEIGHT, WIDTH, CV_8UC3, cv::Scalar(200, 120, 40 * p_frame));
	REQUIRE(cv::imwrite((p_folder / name(p_frame, "color.jpg")).string(), bgr));
	cv::Mat depth(HEIGHT, WIDTH, CV_16UC1, cv::Scalar(1000 + 10 * p_frame));
	depth.at<uint16_t>(0, 0) = 0;
	REQUIRE(cv::imwrite((p_folder / name(p_frame, "depth.png")).string(), depth));
	if (p_pose) {
		write_text(p_folder / name(p_frame, "pose.txt"), pose_text(true_pose(p_frame)));
	}
}

// A fresh folder under build/ with p_count frames and camera-intrinsics.txt.
fs::path write_folder(const std::string &p_name, int p_count) {
	const fs::path folder = fs::path("build") / "test-recording" / p_name;
	std::error_code ec;
	fs::remove_all(folder, ec);
	fs::create_directories(folder);
	write_text(folder / "camera-intrinsics.txt", "5.000000000000000000e+01 0.000000000000000000e+00 3.150000000000000000e+01\n"
												 "0.000000000000000000e+00 5.100000000000000000e+01 2.350000000000000000e+01\n"
												 "0.000000000000000000e+00 0.000000000000000000e+00 1.000000000000000000e+00\n");
	for (int i = 0; i < p_count; i++) {
		write_frame(folder, i);
	}
	return folder;
}

const RecordingIssue *find_issue(const RecordingReader &p_reader, const std::string &p_part) {
	for (const RecordingIssue &issue : p_reader.get_issues()) {
		if (contains(to_string(issue), p_part)) {
			return &issue;
		}
	}
	return nullptr;
}

double rotation_distance(const glm::dquat &p_a, const glm::dquat &p_b) {
	return std::min(glm::length(p_a - p_b), glm::length(p_a + p_b));
}

bool real_data_missing() {
	const bool missing = !fs::exists(REAL_FOLDER + "/camera-intrinsics.txt");
	if (missing) {
		std::fprintf(stderr, "test_recording_frames_dataset: skipping the real-data test: %s is missing\n", REAL_FOLDER.c_str());
	}
	return missing;
}
const bool k_real_data_missing = real_data_missing();

} // namespace

TEST_CASE("frames dataset: frames, times, intrinsics, depth in metres and poses as ground truth") {
	const fs::path folder = write_folder("frames_good", 4);
	RecordingReader reader;
	const RecordingStatus opened = open_frames_dataset(folder.string(), &reader);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));
	CHECK_FALSE(reader.has_room());
	CHECK_FALSE(reader.get_rig().has_fisheye());
	CHECK(reader.fisheye_count() == 0);
	const PinholeParams &rgb = reader.get_rig().rgb;
	CHECK(rgb.width == WIDTH);
	CHECK(rgb.height == HEIGHT);
	CHECK(rgb.fx == 50.0);
	CHECK(rgb.fy == 51.0);
	CHECK(rgb.cx == 31.5);
	CHECK(rgb.cy == 23.5);
	CHECK(rgb.k1 == 0.0);
	CHECK(reader.get_rig().depth_scale_m == 0.001);

	REQUIRE(reader.rgbd_count() == 4);
	CHECK(reader.get_events().size() == 4);
	for (int i = 0; i < 4; i++) {
		CAPTURE(i);
		CHECK(reader.get_rgbd_ref(size_t(i)).rgb.timestamp_s == doctest::Approx(i / 30.0));
		const RgbdFrameResult frame = reader.read_rgbd(size_t(i));
		REQUIRE_MESSAGE(frame.ok, frame.error);
		CHECK(frame.frame.rgb.type() == CV_8UC3);
		const cv::Vec3b colour = frame.frame.rgb.at<cv::Vec3b>(20, 30); // R, G, B
		CHECK(std::abs(int(colour[0]) - 40 * i) <= 3);
		CHECK(std::abs(int(colour[1]) - 120) <= 3);
		CHECK(std::abs(int(colour[2]) - 200) <= 3);
		CHECK(frame.frame.depth_m.at<float>(20, 30) == doctest::Approx((1000 + 10 * i) * 0.001));
		CHECK(std::isnan(frame.frame.depth_m.at<float>(0, 0)));
	}

	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	REQUIRE(truth.size() == 4);
	for (int i = 0; i < 4; i++) {
		CAPTURE(i);
		const TimedPose &sample = truth.get_samples()[size_t(i)];
		CHECK(sample.t_s == doctest::Approx(i / 30.0));
		CHECK(glm::length(sample.world_from_camera.translation - true_pose(i).translation) < 1e-12);
		CHECK(rotation_distance(sample.world_from_camera.rotation, true_pose(i).rotation) < 1e-12);
	}
}

TEST_CASE("frames dataset: options: frame rate, depth scale, intrinsics instead of the file") {
	const fs::path folder = write_folder("frames_options", 3);
	fs::remove(folder / "camera-intrinsics.txt");
	RecordingReader reader;
	RecordingStatus opened = open_frames_dataset(folder.string(), &reader);
	CHECK_FALSE(opened.ok);
	CHECK(contains(opened.error, (folder / "camera-intrinsics.txt").string() + ": missing"));

	FramesDatasetOptions options;
	options.override_intrinsics = true;
	options.intrinsics.fx = 60.0;
	options.intrinsics.fy = 61.0;
	options.intrinsics.cx = 32.0;
	options.intrinsics.cy = 24.0;
	options.depth_scale_m = 0.0002;
	options.frame_rate_hz = 15.0;
	opened = open_frames_dataset(folder.string(), &reader, options);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK(reader.get_rig().rgb.fx == 60.0);
	CHECK(reader.get_rig().rgb.width == WIDTH); // from the images
	CHECK(reader.get_rig().depth_scale_m == 0.0002);
	REQUIRE(reader.rgbd_count() == 3);
	CHECK(reader.get_rgbd_ref(2).rgb.timestamp_s == doctest::Approx(2.0 / 15.0));
	const RgbdFrameResult frame = reader.read_rgbd(1);
	REQUIRE_MESSAGE(frame.ok, frame.error);
	CHECK(frame.frame.depth_m.at<float>(5, 5) == doctest::Approx(1010 * 0.0002));

	options.depth_scale_m = 0.0;
	opened = open_frames_dataset(folder.string(), &reader, options);
	CHECK_FALSE(opened.ok);
	CHECK(contains(opened.error, "depth_scale_m: must be positive"));
	options.depth_scale_m = 0.001;
	options.frame_rate_hz = -30.0;
	CHECK(contains(open_frames_dataset(folder.string(), &reader, options).error, "frame_rate_hz: must be positive"));
	options.frame_rate_hz = 30.0;
	options.intrinsics.fx = 0.0;
	CHECK(contains(open_frames_dataset(folder.string(), &reader, options).error, "FramesDatasetOptions::intrinsics"));
}

TEST_CASE("frames dataset: an unusable folder or camera-intrinsics.txt fails open, naming the file") {
	RecordingReader reader;
	RecordingStatus opened = open_frames_dataset("build/test-recording/no_such_frames", &reader);
	CHECK_FALSE(opened.ok);
	CHECK(contains(opened.error, "no_such_frames: no such frames folder"));

	const fs::path empty = write_folder("frames_none", 0);
	opened = open_frames_dataset(empty.string(), &reader);
	CHECK_FALSE(opened.ok);
	CHECK(contains(opened.error, "no frame-NNNNNN.depth.png"));

	const fs::path folder = write_folder("frames_bad_k", 2);
	const std::string k_path = (folder / "camera-intrinsics.txt").string();
	struct Case {
		const char *name;
		const char *text;
		const char *hint;
	};
	const Case cases[] = {
		{ "two_rows", "585 0 320\n0 585 240\n", "2 rows, expected the 3 of a 3x3 matrix" },
		{ "short_row", "585 0 320\n0 585\n0 0 1\n", "camera-intrinsics.txt:2: expected 3 numbers, got 2" },
		{ "text", "585 0 320\n0 fy 240\n0 0 1\n", "camera-intrinsics.txt:2: 'fy' is not a finite number" },
		{ "skew", "585 1.5 320\n0 585 240\n0 0 1\n", "not a pinhole K without skew" },
		{ "negative_f", "-585 0 320\n0 585 240\n0 0 1\n", "fx and fy (K[0][0], K[1][1]) must be positive" },
		{ "four_rows", "585 0 320\n0 585 240\n0 0 1\n0 0 1\n", ":4: more than the 3 rows" },
	};
	for (const Case &c : cases) {
		const std::string case_name = c.name;
		CAPTURE(case_name);
		write_text(k_path, c.text);
		opened = open_frames_dataset(folder.string(), &reader);
		CHECK_FALSE(opened.ok);
		CAPTURE(opened.error);
		CHECK(contains(opened.error, k_path));
		CHECK(contains(opened.error, c.hint));
	}
}

TEST_CASE("frames dataset: gaps, missing and broken images and poses are issues naming the file; the rest plays") {
	const fs::path folder = write_folder("frames_damaged", 9);
	// Frames 3 and 4 gone entirely: a gap; 6 without its colour image; 7's depth the wrong size;
	// 8's colour JPEG cut short.
	for (int frame : { 3, 4 }) {
		for (const char *kind : { "color.jpg", "depth.png", "pose.txt" }) {
			fs::remove(folder / name(frame, kind));
		}
	}
	fs::remove(folder / name(6, "color.jpg"));
	REQUIRE(cv::imwrite((folder / name(7, "depth.png")).string(), cv::Mat(HEIGHT / 2, WIDTH / 2, CV_16UC1, cv::Scalar(1000))));
	const std::string jpeg = read_text(folder / name(8, "color.jpg"));
	write_text(folder / name(8, "color.jpg"), jpeg.substr(0, jpeg.size() / 2));
	// Poses: 1 has a short row, 2 a wrong last row, 5 -inf (how some datasets mark a frame without one).
	write_text(folder / name(1, "pose.txt"), "1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n");
	write_text(folder / name(2, "pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n");
	write_text(folder / name(5, "pose.txt"), "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n0 0 0 1\n");

	RecordingReader reader;
	const RecordingStatus opened = open_frames_dataset(folder.string(), &reader);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	const std::string issues = all_issues(reader);
	CAPTURE(issues);

	const RecordingIssue *gap = find_issue(reader, "gap in the numbering");
	REQUIRE(gap != nullptr);
	CHECK(contains(gap->message, "frame-000003.* to frame-000004.* missing"));
	const RecordingIssue *no_colour = find_issue(reader, name(6, "color.jpg"));
	REQUIRE(no_colour != nullptr);
	CHECK(contains(no_colour->message, "missing; RGB-D frame skipped"));
	const RecordingIssue *small = find_issue(reader, name(7, "depth.png"));
	REQUIRE(small != nullptr);
	CHECK(contains(small->message, "32x24 pixels, but the rig's RGB-D camera is 64x48"));
	const RecordingIssue *cut = find_issue(reader, name(8, "color.jpg"));
	REQUIRE(cut != nullptr);
	CHECK(contains(cut->message, "truncated"));
	const RecordingIssue *short_row = find_issue(reader, name(1, "pose.txt"));
	REQUIRE(short_row != nullptr);
	CHECK(short_row->line == 2);
	CHECK(contains(short_row->message, "expected 4 numbers, got 3; no ground-truth pose at this frame"));
	const RecordingIssue *last_row = find_issue(reader, name(2, "pose.txt"));
	REQUIRE(last_row != nullptr);
	CHECK(contains(last_row->message, "the last row must be 0 0 0 1"));
	const RecordingIssue *infinite = find_issue(reader, name(5, "pose.txt"));
	REQUIRE(infinite != nullptr);
	CHECK(contains(infinite->message, "'-inf' is not a finite number"));

	// Frames 0, 1, 2 and 5 play, at their own numbers' times.
	REQUIRE(reader.rgbd_count() == 4);
	CHECK(reader.get_rgbd_ref(3).rgb.timestamp_s == doctest::Approx(5.0 / 30.0));
	for (size_t i = 0; i < reader.rgbd_count(); i++) {
		const RgbdFrameResult frame = reader.read_rgbd(i);
		CHECK_MESSAGE(frame.ok, frame.error);
	}
	// Ground truth at frames 0, 6, 7 and 8 (their poses are good even where an image is not).
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	REQUIRE(truth.size() == 4);
	CHECK(truth.get_samples()[1].t_s == doctest::Approx(6.0 / 30.0));

	// A JPEG that goes bad after open is an error on reading that frame, naming the file.
	write_text(folder / name(5, "color.jpg"), "not a JPEG");
	const RgbdFrameResult broken = reader.read_rgbd(3);
	CHECK_FALSE(broken.ok);
	CHECK(contains(broken.error, name(5, "color.jpg") + ": not a JPEG file"));
}

TEST_CASE("frames dataset: the real 7-Scenes frames in ../shared/data/rgbd-7scenes" * doctest::skip(k_real_data_missing)) {
	RecordingReader reader;
	const RecordingStatus opened = open_frames_dataset(REAL_FOLDER, &reader);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK_MESSAGE(reader.get_issues().empty(), all_issues(reader));
	const PinholeParams &rgb = reader.get_rig().rgb;
	CHECK(rgb.width == 640);
	CHECK(rgb.height == 480);
	CHECK(rgb.fx == 585.0);
	CHECK(rgb.fy == 585.0);
	CHECK(rgb.cx == 320.0);
	CHECK(rgb.cy == 240.0);
	CHECK(reader.rgbd_count() == 400);
	CHECK(reader.get_rgbd_ref(399).rgb.timestamp_s == doctest::Approx(399.0 / 30.0));
	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	CHECK(truth.size() == 400);
	// frame-000000.pose.txt's translation column.
	CHECK(truth.get_samples()[0].world_from_camera.translation.x == doctest::Approx(-0.34045634));
	CHECK(truth.get_samples()[0].world_from_camera.translation.z == doctest::Approx(0.29656917));

	for (size_t index : { size_t(0), size_t(399) }) {
		CAPTURE(index);
		const RgbdFrameResult frame = reader.read_rgbd(index);
		REQUIRE_MESSAGE(frame.ok, frame.error);
		CHECK(frame.frame.rgb.size() == cv::Size(640, 480));
		std::vector<float> depths;
		for (int y = 0; y < 480; y += 4) {
			for (int x = 0; x < 640; x += 4) {
				const float d = frame.frame.depth_m.at<float>(y, x);
				if (std::isfinite(d)) {
					depths.push_back(d);
				}
			}
		}
		REQUIRE(depths.size() > 10000); // most of the image has a reading
		std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
		const float median = depths[depths.size() / 2];
		MESSAGE("frame " << index << ": median depth " << median << " m over " << depths.size() << " samples");
		CHECK(median > 0.4f);
		CHECK(median < 4.0f);
	}
}
