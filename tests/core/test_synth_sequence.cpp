// The synthetic recording (extension/core/synth/synth_sequence.h): the hand-held trajectory, the
// two clocks, what is written and that it reads back, determinism, the calibration views.

#include "io/opencv.h"

#include "camera/pinhole_camera.h"
#include "recording/recording_reader.h"
#include "rig/fisheye_pose.h"
#include "rig/rig.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <opencv2/calib3d.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

using namespace roomprobe;
using namespace roomprobe::synth;
namespace fs = std::filesystem;

namespace {

// The same rig at a quarter of the resolution: cheap recordings for tests of what is written.
Rig small_rig() {
	Rig rig = test_rig();
	rig.rgb.width = 160;
	rig.rgb.height = 120;
	rig.rgb.fx = rig.rgb.fy = 525.0 / 4.0;
	rig.rgb.cx = 79.5;
	rig.rgb.cy = 59.5;
	rig.fisheye = scaled_test_fisheye(4); // 256 x 256
	return rig;
}

// A fresh folder under the system's temporary folder, removed at the end of the scope.
struct TempFolder {
	fs::path path;
	TempFolder() {
		static std::atomic<int> counter { 0 };
		path = fs::temp_directory_path() / ("roomprobe_test_synth_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
		fs::remove_all(path);
	}
	~TempFolder() {
		std::error_code ec;
		fs::remove_all(path, ec);
	}
};

std::string read_bytes(const fs::path &p_path) {
	std::ifstream in(p_path, std::ios::binary);
	return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every file under p_root, relative, sorted.
std::vector<std::string> list_files(const fs::path &p_root) {
	std::vector<std::string> files;
	for (const auto &entry : fs::recursive_directory_iterator(p_root)) {
		if (entry.is_regular_file()) {
			files.push_back(fs::relative(entry.path(), p_root).generic_string());
		}
	}
	std::sort(files.begin(), files.end());
	return files;
}

Scene reference_scene(const std::string &p_name, double p_duration_s = 10.0) {
	SceneOptions options;
	options.duration_s = p_duration_s;
	const SceneResult result = make_scene(p_name, options);
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.scene;
}

SequenceOptions short_sequence(uint64_t p_seed) {
	SequenceOptions options;
	options.duration_s = 0.3;
	options.seed = p_seed;
	options.cubemap_face_size = 16;
	options.calibration_views = false;
	return options;
}

double angle_between(const glm::dquat &p_a, const glm::dquat &p_b) {
	const double d = std::abs(glm::dot(p_a, p_b));
	return 2.0 * std::acos(std::min(1.0, d));
}

} // namespace

TEST_CASE("synth: frame times of the two clocks") {
	SequenceOptions options;
	const std::vector<double> rgbd = rgbd_frame_times(options);
	REQUIRE(rgbd.size() == 300);
	CHECK(rgbd.front() == 0.0);
	CHECK(rgbd.back() == doctest::Approx(299.0 / 30.0));
	const std::vector<double> fisheye = fisheye_frame_times(options, 0.0137);
	CHECK(fisheye.size() == 120);
	CHECK(fisheye.front() == 0.0);
	for (double t : fisheye) {
		CHECK(t + 0.0137 >= rgbd.front());
		CHECK(t + 0.0137 <= rgbd.back());
	}
	// A clock ahead of the RGB-D clock: the first fisheye frames would come before the first RGB-D one.
	const std::vector<double> ahead = fisheye_frame_times(options, -0.2);
	REQUIRE(!ahead.empty());
	CHECK(ahead.front() - 0.2 >= 0.0);
	CHECK(ahead.front() == doctest::Approx(3.0 / 12.0));
}

TEST_CASE("synth: the hand-held trajectory orbits the table smoothly, looking at it, the same for the same seed") {
	for (const std::string name : { "two_rooms", "living_room" }) {
		CAPTURE(name);
		const Scene scene = reference_scene(name);
		const HandheldTrajectory trajectory = make_handheld_trajectory(scene, 17);
		const HandheldTrajectory same = make_handheld_trajectory(scene, 17);
		const HandheldTrajectory other = make_handheld_trajectory(scene, 18);
		const SynthRenderer renderer(scene);
		REQUIRE(renderer.ok());
		double largest_speed = 0.0, largest_turn = 0.0;
		bool differs = false;
		Pose previous = trajectory.world_from_rgb(0.0);
		for (double t = 0.0; t <= 20.0; t += 1.0 / 30.0) {
			const Pose pose = trajectory.world_from_rgb(t);
			const Pose again = same.world_from_rgb(t);
			CHECK(pose.translation == again.translation);
			CHECK(pose.rotation == again.rotation);
			differs = differs || glm::length(other.world_from_rgb(t).translation - pose.translation) > 0.05;
			const glm::dvec3 p = pose.translation;
			const glm::dvec2 horizontal(p.x - scene.look_target.x, p.z - scene.look_target.z);
			CHECK(glm::length(horizontal) == doctest::Approx(scene.orbit_radius_m).epsilon(0.1));
			CHECK(p.y > 1.2);
			CHECK(p.y < 1.7);
			// Looking at the table: the optical axis within 10 degrees of the target.
			const glm::dvec3 axis = glm::mat3_cast(pose.rotation) * glm::dvec3(0, 0, 1);
			CHECK(std::acos(glm::dot(axis, glm::normalize(scene.look_target - p))) < 10.0 * 3.14159 / 180.0);
			// Inside the room, with room to spare: nothing within 25 cm in any direction.
			for (const glm::dvec3 &d : { glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0), glm::dvec3(0, -1, 0) }) {
				const Hit hit = renderer.intersect(p, d);
				CHECK(hit.hit);
				CHECK(hit.distance > 0.25);
			}
			// Hand speeds: under 1.2 m/s and 90 degrees/s.
			largest_speed = std::max(largest_speed, glm::length(pose.translation - previous.translation) * 30.0);
			largest_turn = std::max(largest_turn, angle_between(pose.rotation, previous.rotation) * 30.0 * 180.0 / 3.14159);
			previous = pose;
		}
		CHECK(differs);
		CHECK(largest_speed < 1.2);
		CHECK(largest_speed > 0.2);
		CHECK(largest_turn < 90.0);
	}
}

TEST_CASE("synth: --loop turns once round the table over the recording and ends where it began") {
	// scene.orbit_loop_s (synth --loop): loop closure needs a sweep that comes back with truth. The
	// hand's wobble (radius +-8 cm, angle +-0.08 rad, height +-10 cm) keeps the end within about
	// 30 cm of the start, seeing the same table from the same side.
	for (const std::string name : { "two_rooms", "living_room" }) {
		CAPTURE(name);
		Scene scene = reference_scene(name);
		scene.orbit_loop_s = 60.0;
		const HandheldTrajectory loop = make_handheld_trajectory(scene, 1);
		const Pose start = loop.world_from_rgb(0.0), end = loop.world_from_rgb(60.0), half = loop.world_from_rgb(30.0);
		CHECK(glm::length(end.translation - start.translation) < 0.3);
		CHECK(angle_between(end.rotation, start.rotation) < 15.0 * 3.14159 / 180.0);
		CHECK(glm::length(half.translation - start.translation) > 2.0 * scene.orbit_radius_m - 0.4); // the far side
		CHECK(std::abs(loop.angular_speed_rad_s) == doctest::Approx(2.0 * 3.14159265358979 / 60.0));
	}
}

TEST_CASE("synth: the room sweep walks its path turning round, and shows every wall, the floor and both rooms") {
	for (const std::string name : { "two_rooms", "living_room" }) {
		CAPTURE(name);
		Scene scene = reference_scene(name);
		scene.trajectory = TrajectoryKind::RoomSweep;
		const RoomSweepParams &sweep = scene.room_sweep;
		REQUIRE(sweep.path_xz.size() >= 2);
		const HandheldTrajectory trajectory = make_handheld_trajectory(scene, 5);
		const HandheldTrajectory other = make_handheld_trajectory(scene, 6);
		const SynthRenderer renderer(scene);
		REQUIRE(renderer.ok());
		const std::vector<Vec2> &corners = scene.room.floorplan.points;
		const double ceiling_m = scene.room.floorplan.ceiling_height_m;
		std::vector<int> edge_hits(corners.size(), 0);
		std::array<int, 8> headings = {};
		int floor_hits = 0, rays = 0;
		double largest_speed = 0.0, largest_turn = 0.0;
		bool differs = false;
		Pose previous = trajectory.world_from_rgb(0.0);
		for (int i = 0; i <= 300; ++i) {
			const double t = i / 30.0;
			const Pose pose = trajectory.world_from_rgb(t);
			const glm::dvec3 p = pose.translation;
			differs = differs || angle_between(other.world_from_rgb(t).rotation, pose.rotation) > 0.2;
			CHECK(p.y > 1.3);
			CHECK(p.y < 1.6);
			// Clear of walls and furniture: nothing within 30 cm in any horizontal direction.
			for (const glm::dvec3 &d : { glm::dvec3(1, 0, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, 0, -1), glm::dvec3(0, -1, 0) }) {
				const Hit hit = renderer.intersect(p, d);
				CHECK(hit.hit);
				CHECK(hit.distance > 0.3);
			}
			const glm::dmat3 rotation = glm::mat3_cast(pose.rotation);
			const glm::dvec3 axis = rotation * glm::dvec3(0, 0, 1);
			// Pitched down 3 to 30 degrees: the floor, then the walls.
			const double pitch_deg = std::asin(axis.y) * 180.0 / 3.14159;
			CHECK(pitch_deg < -3.0);
			CHECK(pitch_deg > -30.0);
			const double heading = std::atan2(axis.z, axis.x) + 3.14159265;
			headings[std::min(7, static_cast<int>(heading / (2.0 * 3.14159265) * 8.0))]++;
			// What the RGB-D camera sees (a grid over its 63 x 49 degree view, out to 6 m): each wall's stretch.
			if (i % 3 == 0) {
				for (int u = -3; u <= 3; ++u) {
					for (int v = -3; v <= 3; ++v) {
						const glm::dvec3 ray = rotation * glm::normalize(glm::dvec3(std::tan(u * 0.18), std::tan(v * 0.14), 1.0));
						const Hit hit = renderer.intersect(p, ray);
						if (!hit.hit || hit.distance > 6.0) {
							continue;
						}
						++rays;
						floor_hits += hit.point.y < 0.01 ? 1 : 0;
						for (size_t e = 0; e < corners.size(); ++e) {
							const Vec2 a = corners[e], b = corners[(e + 1) % corners.size()];
							const glm::dvec2 ab(b.x - a.x, b.y - a.y), ap(hit.point.x - a.x, hit.point.z - a.y);
							const double s = glm::dot(ap, ab) / glm::dot(ab, ab);
							const double off = std::abs(ab.x * ap.y - ab.y * ap.x) / glm::length(ab);
							if (s > 0.0 && s < 1.0 && off < 0.01 && hit.point.y > 0.05 && hit.point.y < ceiling_m - 0.05) {
								edge_hits[e]++;
							}
						}
					}
				}
			}
			if (i > 0) {
				largest_speed = std::max(largest_speed, glm::length(pose.translation - previous.translation) * 30.0);
				largest_turn = std::max(largest_turn, angle_between(pose.rotation, previous.rotation) * 30.0 * 180.0 / 3.14159);
			}
			previous = pose;
		}
		// At rest at the path's ends: its first point at 0 s, its last at walk_s, within the hand's wobble.
		const glm::dvec3 start = trajectory.world_from_rgb(0.0).translation, end = trajectory.world_from_rgb(sweep.walk_s).translation;
		CHECK(glm::length(glm::dvec2(start.x, start.z) - sweep.path_xz.front()) < 0.1);
		CHECK(glm::length(glm::dvec2(end.x, end.z) - sweep.path_xz.back()) < 0.1);
		// Turned all round: every eighth of the compass faced.
		for (int h = 0; h < 8; ++h) {
			CAPTURE(h);
			CHECK(headings[h] > 0);
		}
		// Every wall a metre or longer seen in twenty rays or more (of the 49 a view, every tenth of a
		// second); the floor in one ray in twenty.
		for (size_t e = 0; e < corners.size(); ++e) {
			const Vec2 a = corners[e], b = corners[(e + 1) % corners.size()];
			if (std::hypot(b.x - a.x, b.y - a.y) >= 1.0) {
				CAPTURE(e);
				CHECK(edge_hits[e] > 20);
			}
		}
		CHECK(floor_hits > rays / 20);
		CHECK(differs);
		CHECK(largest_speed < 1.2);
		CHECK(largest_turn < 90.0);
	}
}

TEST_CASE("synth: a recording reads back: frames, both clocks, ground-truth poses and cubemaps") {
	const Rig rig = test_rig();
	const Scene scene = reference_scene("living_room", 0.3);
	TempFolder folder;
	const SequenceOptions options = short_sequence(4);
	const SequenceResult result = write_sequence(folder.path.string(), rig, scene, options);
	REQUIRE_MESSAGE(result.ok, result.error);
	CHECK(result.timings.rgbd_frames == 9);
	// Fisheye frames at k / 12 s on their clock, k / 12 + 0.0137 s on the RGB-D clock, up to 8 / 30 s.
	CHECK(result.timings.fisheye_frames == 4);
	CHECK(result.timings.cubemaps == 4);

	cv::FileStorage info((folder.path / "synth.yaml").string(), cv::FileStorage::READ);
	REQUIRE(info.isOpened());
	CHECK(std::string(info["scene"]) == "living_room");
	CHECK(double(info["light_switch_s"]) == doctest::Approx(0.15));

	RecordingReader reader;
	const RecordingStatus status = reader.open(folder.path.string());
	REQUIRE_MESSAGE(status.ok, status.error);
	for (const RecordingIssue &issue : reader.get_issues()) {
		MESSAGE(to_string(issue));
	}
	CHECK(reader.get_issues().empty());
	CHECK(reader.rgbd_count() == 9);
	CHECK(reader.fisheye_count() == 4);
	CHECK(reader.get_fisheye_ref(1).timestamp_s == doctest::Approx(1.0 / 12.0));
	REQUIRE(reader.has_room());
	REQUIRE(reader.get_room().probes.size() == 1);
	CHECK(reader.get_room().probes[0] == scene.probe_position);
	CHECK(reader.get_rig().fisheye_time_offset_s == doctest::Approx(0.0137));

	// The frames are what the renderer makes for the true poses.
	const HandheldTrajectory trajectory = make_handheld_trajectory(scene, options.seed);
	const RgbdFrameResult frame = reader.read_rgbd(2);
	REQUIRE_MESSAGE(frame.ok, frame.error);
	const SynthRenderer renderer(scene);
	RgbdOptions rgbd_options;
	rgbd_options.noise_seed = 12345; // the colour does not depend on it
	const RgbdImage expected = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, trajectory.world_from_rgb(2.0 / 30.0), 2.0 / 30.0, rgbd_options);
	CHECK(cv::norm(frame.frame.rgb, expected.rgb, cv::NORM_INF) == 0);
	// Depth reads back in metres, NaN for no reading, within the noise of the noise-free depth.
	int readings = 0;
	for (int y = 0; y < 480; y += 8) {
		for (int x = 0; x < 640; x += 8) {
			const float d = frame.frame.depth_m.at<float>(y, x);
			if (std::isnan(d)) {
				continue;
			}
			const float truth = expected.depth_true_m.at<float>(y, x);
			CHECK(std::abs(d - truth) < 5.0 * kinect_depth_sigma_m(truth) + 0.001);
			++readings;
		}
	}
	CHECK(readings > 3000);

	// Ground-truth poses: RGB-D on its clock, the fisheye on its own, related by the extrinsic
	// and the clock offset (what fisheye_pose_at computes from the RGB-D trajectory).
	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Rgbd));
	REQUIRE(reader.has_ground_truth_trajectory(RecordingStream::Fisheye));
	const Trajectory &rgb_truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	const Trajectory &fisheye_truth = reader.ground_truth_trajectory(RecordingStream::Fisheye);
	CHECK(rgb_truth.size() == 9);
	REQUIRE(fisheye_truth.size() == 4);
	for (const TimedPose &sample : fisheye_truth.get_samples()) {
		const Pose exact = compose(trajectory.world_from_rgb(sample.t_s + rig.fisheye_time_offset_s), rig.rgb_from_fisheye);
		CHECK(glm::length(sample.world_from_camera.translation - exact.translation) < 1e-9);
		Pose interpolated;
		std::string error;
		REQUIRE_MESSAGE(fisheye_pose_at(rgb_truth, reader.get_rig(), sample.t_s, &interpolated, &error), error);
		CHECK(glm::length(interpolated.translation - exact.translation) < 0.003);
		CHECK(angle_between(interpolated.rotation, exact.rotation) < 0.005);
	}

	// One ground-truth cubemap for every fisheye frame, at its instant on the RGB-D clock.
	REQUIRE(reader.ground_truth_cubemap_count() == 4);
	for (size_t k = 0; k < 4; ++k) {
		const CubemapRef &ref = reader.get_ground_truth_cubemap_ref(k);
		CHECK(ref.timestamp_s == doctest::Approx(reader.get_fisheye_ref(k).timestamp_s + 0.0137));
		CHECK(ref.probe_index == 0);
	}
	const GroundTruthCubemapResult cubemap = reader.ground_truth_cubemap(1);
	REQUIRE_MESSAGE(cubemap.ok, cubemap.error);
	const auto faces = render_cubemap(renderer, scene.probe_position, reader.get_ground_truth_cubemap_ref(1).timestamp_s, 16);
	for (int f = 0; f < 6; ++f) {
		REQUIRE(cubemap.cubemap.faces[f].size() == faces[f].size());
		// Stored as half floats: 11 significant bits.
		cv::Mat difference;
		cv::absdiff(cubemap.cubemap.faces[f], faces[f], difference);
		cv::Mat bound = cv::abs(faces[f]) * (1.0 / 1024.0) + 1e-4;
		const cv::Mat over = difference > bound;
		CHECK(cv::countNonZero(over.reshape(1)) == 0);
		CHECK(!cubemap.cubemap.ldr_faces[f].empty());
	}
}

TEST_CASE("synth: the same seed writes the same bytes; another seed does not") {
	const Rig rig = small_rig();
	const Scene scene = reference_scene("two_rooms", 0.3);
	TempFolder a, b, c;
	REQUIRE(write_sequence(a.path.string(), rig, scene, short_sequence(9)).ok);
	REQUIRE(write_sequence(b.path.string(), rig, scene, short_sequence(9)).ok);
	REQUIRE(write_sequence(c.path.string(), rig, scene, short_sequence(10)).ok);
	const std::vector<std::string> files = list_files(a.path);
	CHECK(files.size() > 20);
	REQUIRE(files == list_files(b.path));
	for (const std::string &file : files) {
		CAPTURE(file);
		CHECK(read_bytes(a.path / file) == read_bytes(b.path / file));
	}
	CHECK(read_bytes(a.path / "rgb/000000.zst") != read_bytes(c.path / "rgb/000000.zst"));
	CHECK(read_bytes(a.path / "depth/000000.zst") != read_bytes(c.path / "depth/000000.zst"));
}

TEST_CASE("synth: a recording is not written into a folder that holds something") {
	const Rig rig = small_rig();
	const Scene scene = reference_scene("two_rooms", 0.3);
	TempFolder folder;
	fs::create_directories(folder.path);
	std::ofstream(folder.path / "precious.txt") << "keep me\n";
	const SequenceResult result = write_sequence(folder.path.string(), rig, scene, short_sequence(1));
	CHECK_FALSE(result.ok);
	CHECK(result.error.find(folder.path.string()) != std::string::npos);
	CHECK(read_bytes(folder.path / "precious.txt") == "keep me\n");
}

TEST_CASE("synth: checkerboard views: the corners are where boards.yaml says") {
	const Rig rig = test_rig();
	TempFolder folder;
	const CheckerboardSpec board;
	std::vector<std::string> progress;
	const CalibrationResult result =
			write_calibration_views(folder.path.string(), rig, board, 3, FisheyeOptions(), [&](const std::string &p_line) { progress.push_back(p_line); });
	REQUIRE_MESSAGE(result.ok, result.error);
	CHECK(result.views == pinhole_board_poses(board).size() + fisheye_board_poses(board).size() + 2 * pair_board_poses(board).size());
	// The long phase says how far it is: from 0 of N, about every tenth.
	REQUIRE(progress.size() >= 5);
	CHECK(progress.size() <= 12);
	CHECK(progress.front() == "calibration views: 0 of " + std::to_string(result.views) + " rendered");
	cv::FileStorage yaml((folder.path / "calibration/boards.yaml").string(), cv::FileStorage::READ);
	REQUIRE(yaml.isOpened());
	CHECK(int(yaml["board"]["squares_x"]) == board.squares_x);
	const cv::FileNode views = yaml["views"];
	REQUIRE(views.size() == result.views);
	int detected = 0;
	double worst = 0.0, worst_mean = 0.0;
	for (const cv::FileNode &view : views) {
		const std::string camera = view["camera"];
		const std::string image_path = view["image"];
		CAPTURE(image_path);
		std::vector<double> truth;
		view["corners_px"] >> truth;
		REQUIRE(truth.size() == 2 * size_t((board.squares_x - 1) * (board.squares_y - 1)));
		// The pose written is the pose rendered: corner 0 projects where it says.
		std::vector<double> rotation, translation;
		view["camera_from_board"]["rotation_xyzw"] >> rotation;
		view["camera_from_board"]["translation_m"] >> translation;
		REQUIRE(rotation.size() == 4);
		Pose pose;
		pose.rotation = glm::dquat(rotation[3], rotation[0], rotation[1], rotation[2]);
		pose.translation = { translation[0], translation[1], translation[2] };
		if (camera == "rgb") {
			glm::dvec2 pixel;
			REQUIRE(project_pinhole(rig.rgb, transform_point(pose, checkerboard_corners(board)[0]), &pixel));
			CHECK(pixel.x == doctest::Approx(truth[0]));
			CHECK(pixel.y == doctest::Approx(truth[1]));
		}
		// The pinhole views all detect; of the fisheye's, the ones near the axis.
		const cv::Mat image = cv::imread((folder.path / image_path).string(), cv::IMREAD_GRAYSCALE);
		REQUIRE(!image.empty());
		std::vector<cv::Point2f> corners;
		const bool found = cv::findChessboardCorners(image, cv::Size(board.squares_x - 1, board.squares_y - 1), corners,
				cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
		if (camera == "rgb") {
			CHECK(found);
		}
		if (!found) {
			continue;
		}
		cv::cornerSubPix(image, corners, cv::Size(5, 5), cv::Size(-1, -1), cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 0.001));
		// OpenCV may list the corners from either end.
		double forward = 0.0, backward = 0.0, forward_sum = 0.0, backward_sum = 0.0;
		const size_t n = corners.size();
		for (size_t i = 0; i < n; ++i) {
			const double f = std::hypot(corners[i].x - truth[2 * i], corners[i].y - truth[2 * i + 1]);
			const double b = std::hypot(corners[n - 1 - i].x - truth[2 * i], corners[n - 1 - i].y - truth[2 * i + 1]);
			forward = std::max(forward, f);
			backward = std::max(backward, b);
			forward_sum += f;
			backward_sum += b;
		}
		const bool reversed = backward_sum < forward_sum;
		const double error = reversed ? backward : forward;
		const double mean = (reversed ? backward_sum : forward_sum) / n;
		// No bias (a half-pixel convention slip would show here as 0.5 px), and the corner
		// detector's scatter on antialiased edges. The pairs' boards are the farthest (squares of
		// some 20 px, foreshortened), where the classic detector's mean offset reaches 0.07 px.
		cv::Point2d bias(0.0, 0.0);
		for (size_t i = 0; i < n; ++i) {
			const cv::Point2f &c = corners[reversed ? n - 1 - i : i];
			bias += cv::Point2d((c.x - truth[2 * i]) / n, (c.y - truth[2 * i + 1]) / n);
		}
		CHECK(std::abs(bias.x) < 0.1);
		CHECK(std::abs(bias.y) < 0.1);
		CHECK(mean < 0.2);
		CHECK(error < 0.5);
		worst = std::max(worst, error);
		worst_mean = std::max(worst_mean, mean);
		++detected;
	}
	MESSAGE(detected << " of " << views.size() << " views detected; corner error against the truth: largest " << worst << " px, largest mean of a view " << worst_mean << " px");
	CHECK(detected >= 10);
}
