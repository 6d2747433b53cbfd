// The TUM RGB-D dataset reader (recording/tum_dataset.h) on a tiny fake sequence with the real
// files' headers and formats: association as associate.py does it, depth scaling 5000 -> 1 m,
// intrinsics presets, ground truth.

#include "recording/tum_dataset.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

void write_text(const fs::path &p_path, const std::string &p_text) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file << p_text;
}

// Timestamps from the start of freiburg1_xyz. rgb 2 is closer to depth 1 (16.5 ms) than to
// depth 2 (19.7 ms), but depth 1 goes to rgb 1 (15.5 ms) first, as in associate.py. rgb 3 has no
// depth frame within 20 ms.
const char *const RGB_STAMPS[4] = { "1305031102.175304", "1305031102.211214", "1305031102.243211", "1305031102.311000" };
const char *const DEPTH_STAMPS[3] = { "1305031102.160407", "1305031102.226738", "1305031102.262886" };

// Writes the sequence; returns its folder.
fs::path write_fake_tum(const std::string &p_name) {
	const fs::path folder = fs::path("build") / "test-recording" / p_name;
	std::error_code ec;
	fs::remove_all(folder, ec);
	fs::create_directories(folder / "rgb");
	fs::create_directories(folder / "depth");

	std::string rgb_txt = "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n";
	for (int i = 0; i < 4; i++) {
		const std::string name = std::string("rgb/") + RGB_STAMPS[i] + ".png";
		rgb_txt += std::string(RGB_STAMPS[i]) + " " + name + "\n";
		// TUM's colour PNGs are 8-bit RGB; cv::imwrite takes BGR. Pixel (x, y) = (R x % 256, G y % 256, B 10 i).
		cv::Mat bgr(480, 640, CV_8UC3);
		for (int y = 0; y < 480; y++) {
			for (int x = 0; x < 640; x++) {
				bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(10 * i), uchar(y % 256), uchar(x % 256));
			}
		}
		REQUIRE(cv::imwrite((folder / name).string(), bgr));
	}
	write_text(folder / "rgb.txt", rgb_txt);

	std::string depth_txt = "# depth maps\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n";
	for (int i = 0; i < 3; i++) {
		const std::string name = std::string("depth/") + DEPTH_STAMPS[i] + ".png";
		depth_txt += std::string(DEPTH_STAMPS[i]) + " " + name + "\n";
		// 16-bit, 5000 units per metre: 5000 (1 m) everywhere, 12345 (2.469 m) at (10, 20), 0 (no data) at (0, 0).
		cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000 + i));
		depth.at<uint16_t>(20, 10) = 12345;
		depth.at<uint16_t>(0, 0) = 0;
		REQUIRE(cv::imwrite((folder / name).string(), depth));
	}
	write_text(folder / "depth.txt", depth_txt);

	write_text(folder / "groundtruth.txt",
			"# ground truth trajectory\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp tx ty tz qx qy qz qw\n"
			"1305031102.1758 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n"
			"1305031102.1858 1.3303 0.6256 1.6464 0.6579 0.6161 -0.2932 -0.3189\n"
			"1305031102.1958 1.3218 0.6268 1.6368 0.6600 0.6183 -0.2887 -0.3140\n");
	return folder;
}

} // namespace

TEST_CASE("TUM intrinsics presets and camera from the folder name") {
	const PinholeParams ros = tum_camera_intrinsics(TumCamera::RosDefault);
	CHECK(ros.width == 640);
	CHECK(ros.height == 480);
	CHECK(ros.fx == 525.0);
	CHECK(ros.cx == 319.5);
	CHECK(ros.cy == 239.5);
	CHECK(ros.k1 == 0.0);
	const PinholeParams fr1 = tum_camera_intrinsics(TumCamera::Freiburg1);
	CHECK(fr1.fx == 517.306408);
	CHECK(fr1.k3 == 1.163314);
	CHECK(tum_camera_intrinsics(TumCamera::Freiburg2).cy == 249.701764);
	CHECK(tum_camera_intrinsics(TumCamera::Freiburg3).fy == 539.2);

	TumCamera camera = TumCamera::RosDefault;
	CHECK(tum_camera_from_folder_name("/data/rgbd_dataset_freiburg2_desk/", &camera));
	CHECK(camera == TumCamera::Freiburg2);
	CHECK(tum_camera_from_folder_name("tum_fr3_office", &camera));
	CHECK(camera == TumCamera::Freiburg3);
	CHECK_FALSE(tum_camera_from_folder_name("/data/my_room", &camera));
	CHECK_FALSE(tum_camera_from_folder_name("/data/afr1x", &camera));
}

TEST_CASE("TUM dataset: associated frames, depth in metres, ground truth") {
	const fs::path folder = write_fake_tum("rgbd_dataset_freiburg1_tiny");
	TumDatasetOptions options;
	TumCamera camera = TumCamera::RosDefault;
	REQUIRE(tum_camera_from_folder_name(folder.string(), &camera));
	options.rgb = tum_camera_intrinsics(camera);

	RecordingReader reader;
	const RecordingStatus opened = open_tum_dataset(folder.string(), &reader, options);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK(reader.is_open());
	CHECK_FALSE(reader.has_room());
	CHECK(reader.get_rig().rgb.fx == 517.306408);
	CHECK(reader.get_rig().depth_scale_m == doctest::Approx(1.0 / 5000.0).epsilon(1e-15));
	CHECK(reader.fisheye_count() == 0);

	// Association: (rgb 0, depth 0), (rgb 1, depth 1), (rgb 2, depth 2); rgb 3 unpaired.
	REQUIRE(reader.rgbd_count() == 3);
	for (size_t i = 0; i < 3; i++) {
		CHECK(reader.get_rgbd_ref(i).rgb.path == std::string("rgb/") + RGB_STAMPS[i] + ".png");
		CHECK(reader.get_rgbd_ref(i).depth.path == std::string("depth/") + DEPTH_STAMPS[i] + ".png");
	}
	REQUIRE(reader.get_issues().size() == 1);
	CHECK(contains(reader.get_issues()[0].file, "rgb.txt"));
	CHECK(contains(reader.get_issues()[0].message, "1 of 4 frames have no depth frame"));

	// Pixels and depth scaling.
	const RgbdFrameResult frame = reader.read_rgbd(2);
	REQUIRE_MESSAGE(frame.ok, frame.error);
	CHECK(frame.frame.timestamp_s == 1305031102.243211);
	CHECK(frame.frame.depth_timestamp_s == 1305031102.262886);
	CHECK(frame.frame.rgb.at<cv::Vec3b>(7, 300) == cv::Vec3b(uchar(300 % 256), 7, 20)); // R, G, B
	const cv::Mat &depth = frame.frame.depth_m;
	REQUIRE(depth.type() == CV_32FC1);
	REQUIRE(depth.size() == cv::Size(640, 480));
	CHECK(depth.at<float>(100, 100) == doctest::Approx(5002.0 / 5000.0).epsilon(1e-7));
	CHECK(depth.at<float>(20, 10) == doctest::Approx(2.469).epsilon(1e-7));
	CHECK(std::isnan(depth.at<float>(0, 0)));
	const RgbdFrameResult first = reader.read_rgbd(0);
	REQUIRE(first.ok);
	CHECK(first.frame.depth_m.at<float>(1, 1) == 1.0f); // 5000 units: exactly one metre

	// Events: the RGB-D frames only, in order.
	REQUIRE(reader.get_events().size() == 3);
	CHECK(reader.get_events()[2].time_s == 1305031102.243211);

	// Ground truth: the colour camera's poses in the motion-capture world.
	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	CHECK_FALSE(reader.has_ground_truth_trajectory(RecordingStream::Fisheye));
	const Trajectory &trajectory = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	REQUIRE(trajectory.size() == 3);
	CHECK(trajectory.get_samples()[0].t_s == 1305031102.1758);
	CHECK(trajectory.get_samples()[0].world_from_camera.translation.x == doctest::Approx(1.3405));
	CHECK(std::abs(glm::length(trajectory.get_samples()[1].world_from_camera.rotation) - 1.0) < 1e-12);
}

TEST_CASE("TUM dataset: damaged sequences") {
	const fs::path folder = write_fake_tum("rgbd_dataset_freiburg1_damaged");
	fs::remove(folder / "groundtruth.txt");
	fs::remove(folder / (std::string("rgb/") + RGB_STAMPS[1] + ".png"));
	RecordingReader reader;
	RecordingStatus opened = open_tum_dataset(folder.string(), &reader);
	REQUIRE_MESSAGE(opened.ok, opened.error);
	CHECK(reader.get_rig().rgb.fx == 525.0); // the ROS default
	CHECK(reader.rgbd_count() == 2);
	CHECK_FALSE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	bool missing_image = false;
	bool missing_groundtruth = false;
	for (const RecordingIssue &issue : reader.get_issues()) {
		missing_image = missing_image || (contains(issue.message, RGB_STAMPS[1]) && contains(issue.message, "missing") && issue.line == 5);
		missing_groundtruth = missing_groundtruth || (contains(issue.file, "groundtruth.txt") && contains(issue.message, "missing"));
	}
	CHECK(missing_image);
	CHECK(missing_groundtruth);
	for (size_t i = 0; i < reader.rgbd_count(); i++) {
		CHECK(reader.read_rgbd(i).ok);
	}

	// The images are not the size of the intrinsics given.
	TumDatasetOptions options;
	options.rgb.width = 320;
	options.rgb.height = 240;
	opened = open_tum_dataset(folder.string(), &reader, options);
	REQUIRE(opened.ok);
	CHECK(reader.rgbd_count() == 0);
	bool wrong_size = false;
	for (const RecordingIssue &issue : reader.get_issues()) {
		wrong_size = wrong_size || (contains(issue.message, "640x480") && contains(issue.message, "320x240"));
	}
	CHECK(wrong_size);

	fs::remove(folder / "depth.txt");
	opened = open_tum_dataset(folder.string(), &reader);
	CHECK_FALSE(opened.ok);
	CHECK(contains(opened.error, "depth.txt"));
	CHECK_FALSE(reader.is_open());
}
