// Trajectories (rig/trajectory.h): validation, pose_at between samples and TUM files.

#include "rig/trajectory.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <unistd.h>

#include <cmath>
#include <initializer_list>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

double rotation_distance(const glm::dquat &p_a, const glm::dquat &p_b) {
	return std::min(glm::length(p_a - p_b), glm::length(p_a + p_b));
}

// A file under the temp directory, removed when the test is done.
struct TempFile {
	fs::path path;
	explicit TempFile(const std::string &p_name) :
			path(fs::temp_directory_path() / ("roomprobe_" + std::to_string(getpid()) + "_" + p_name)) {}
	~TempFile() {
		std::error_code ec;
		fs::remove(path, ec);
	}
	std::string write(const std::string &p_text) const {
		std::ofstream(path) << p_text;
		return path.string();
	}
};

// Constant linear and angular velocity: lerp + slerp between any two samples is exact.
Pose motion_at(double p_t) {
	Pose pose;
	const glm::dquat start = glm::normalize(glm::dquat(0.6, -0.2, 0.7, 0.3));
	pose.rotation = glm::angleAxis(0.9 * p_t, glm::normalize(glm::dvec3(0.1, 1.0, 0.2))) * start;
	pose.translation = glm::dvec3(1.0, 1.4, -0.5) + glm::dvec3(-0.2, 0.01, 0.45) * p_t;
	return pose;
}

// Irregular frame times around 30 Hz from p_start, as a real camera's.
std::vector<TimedPose> motion_samples(double p_start, int p_count, unsigned p_seed) {
	std::mt19937 rng(p_seed);
	std::uniform_real_distribution<double> jitter(-0.008, 0.008);
	std::vector<TimedPose> samples;
	double t = p_start;
	for (int i = 0; i < p_count; i++) {
		samples.push_back({ t, motion_at(t - p_start) });
		t += 1.0 / 30.0 + jitter(rng);
	}
	return samples;
}

void check_same_pose(const Pose &p_actual, const Pose &p_expected, double p_tolerance) {
	CHECK(rotation_distance(p_actual.rotation, p_expected.rotation) < p_tolerance);
	CHECK(glm::length(p_actual.translation - p_expected.translation) < p_tolerance);
}

} // namespace

TEST_CASE("trajectory: pose_at between samples equals the analytic motion") {
	Trajectory trajectory;
	std::string error;
	REQUIRE(trajectory.set_samples(motion_samples(0.0, 60, 1), &error));
	CHECK(error.empty());
	CHECK(trajectory.size() == 60);
	const double start = trajectory.get_start_s();
	const double end = trajectory.get_end_s();
	CHECK(start == 0.0);

	std::mt19937 rng(2);
	std::uniform_real_distribution<double> when(start, end);
	for (int i = 0; i < 1000; i++) {
		const double t = when(rng);
		CAPTURE(t);
		Pose pose;
		REQUIRE(trajectory.pose_at(t, &pose, &error));
		check_same_pose(pose, motion_at(t), 1e-9);
	}
	// At a sample's own time, that sample exactly.
	for (const TimedPose &sample : trajectory.get_samples()) {
		Pose pose;
		REQUIRE(trajectory.pose_at(sample.t_s, &pose, &error));
		CHECK(pose.rotation == sample.world_from_camera.rotation);
		CHECK(pose.translation == sample.world_from_camera.translation);
	}
}

TEST_CASE("trajectory: outside its time range pose_at is an error, within the tolerance an extrapolation") {
	Trajectory trajectory;
	std::string error;
	REQUIRE(trajectory.set_samples(motion_samples(10.0, 30, 3), &error));
	const double start = trajectory.get_start_s();
	const double end = trajectory.get_end_s();

	Pose untouched;
	untouched.translation = glm::dvec3(123.0);
	for (const double t : { start - 1e-6, end + 1e-6, start - 5.0, end + 100.0, double(NAN) }) {
		CAPTURE(t);
		Pose pose = untouched;
		error.clear();
		CHECK_FALSE(trajectory.pose_at(t, &pose, &error));
		CHECK(pose.translation == untouched.translation);
		CHECK_FALSE(error.empty());
	}
	error.clear();
	Pose pose;
	CHECK_FALSE(trajectory.pose_at(end + 0.5, &pose, &error));
	CHECK(contains(error, "outside the trajectory"));

	// Within the tolerance: the end pair extended at constant velocity (exact for this motion).
	REQUIRE(trajectory.pose_at(end + 0.01, &pose, &error, 0.02));
	check_same_pose(pose, motion_at(end + 0.01 - 10.0), 1e-9);
	REQUIRE(trajectory.pose_at(start - 0.015, &pose, &error, 0.02));
	check_same_pose(pose, motion_at(start - 0.015 - 10.0), 1e-9);
	CHECK_FALSE(trajectory.pose_at(end + 0.03, &pose, &error, 0.02));
	CHECK(contains(error, "tolerance"));

	Trajectory empty;
	CHECK_FALSE(empty.pose_at(0.0, &pose, &error));
	CHECK(contains(error, "empty"));

	// One sample: only its own time (or within the tolerance, its pose held).
	Trajectory single;
	REQUIRE(single.set_samples({ { 5.0, motion_at(1.0) } }, &error));
	REQUIRE(single.pose_at(5.0, &pose, &error));
	check_same_pose(pose, motion_at(1.0), 0.0 + 1e-15);
	CHECK_FALSE(single.pose_at(5.001, &pose, &error));
	REQUIRE(single.pose_at(5.001, &pose, &error, 0.01));
	check_same_pose(pose, motion_at(1.0), 1e-15);
}

TEST_CASE("trajectory: samples must be strictly increasing, finite and unit; errors name the index") {
	std::string error;
	Trajectory trajectory;
	REQUIRE(trajectory.set_samples(motion_samples(0.0, 5, 4), &error));

	std::vector<TimedPose> repeated = motion_samples(0.0, 5, 4);
	repeated[3].t_s = repeated[2].t_s;
	CHECK_FALSE(trajectory.set_samples(repeated, &error));
	CHECK(contains(error, "sample 3"));
	CHECK(trajectory.size() == 5); // unchanged

	std::vector<TimedPose> backwards = motion_samples(0.0, 5, 4);
	std::swap(backwards[1], backwards[2]);
	CHECK_FALSE(trajectory.set_samples(backwards, &error));
	CHECK(contains(error, "sample 2"));

	std::vector<TimedPose> not_finite = motion_samples(0.0, 5, 4);
	not_finite[4].world_from_camera.translation.z = INFINITY;
	CHECK_FALSE(trajectory.set_samples(not_finite, &error));
	CHECK(contains(error, "sample 4"));
	CHECK(contains(error, "not finite"));

	std::vector<TimedPose> nan_time = motion_samples(0.0, 5, 4);
	nan_time[0].t_s = NAN;
	CHECK_FALSE(trajectory.set_samples(nan_time, &error));
	CHECK(contains(error, "sample 0"));

	std::vector<TimedPose> not_unit = motion_samples(0.0, 5, 4);
	not_unit[1].world_from_camera.rotation *= 1.01;
	CHECK_FALSE(trajectory.set_samples(not_unit, &error));
	CHECK(contains(error, "sample 1"));
	CHECK(contains(error, "unit quaternion"));

	// Within the tolerance the rotation is normalised.
	std::vector<TimedPose> nearly_unit = motion_samples(0.0, 5, 4);
	nearly_unit[1].world_from_camera.rotation *= 1.0 + 5e-7;
	REQUIRE(trajectory.set_samples(nearly_unit, &error));
	CHECK(std::abs(glm::length(trajectory.get_samples()[1].world_from_camera.rotation) - 1.0) < 1e-15);

	// append keeps the same rules.
	Trajectory live;
	REQUIRE(live.append({ 1.0, motion_at(0.0) }, &error));
	REQUIRE(live.append({ 1.1, motion_at(0.1) }, &error));
	CHECK_FALSE(live.append({ 1.1, motion_at(0.2) }, &error));
	CHECK(contains(error, "sample 2"));
	CHECK(live.size() == 2);
}

TEST_CASE("trajectory: TUM files round trip at full precision") {
	TempFile file("roundtrip_trajectory.txt");
	Trajectory trajectory;
	std::string error;
	// Timestamps like the TUM RGB-D benchmark's (seconds since 1970).
	REQUIRE(trajectory.set_samples(motion_samples(1305031102.175304, 200, 5), &error));
	REQUIRE(save_tum_trajectory(file.path.string(), trajectory) == "");

	const TrajectoryLoadResult loaded = load_tum_trajectory(file.path.string());
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	REQUIRE(loaded.trajectory.size() == trajectory.size());
	for (size_t i = 0; i < trajectory.size(); i++) {
		const TimedPose &a = trajectory.get_samples()[i];
		const TimedPose &b = loaded.trajectory.get_samples()[i];
		CAPTURE(i);
		CHECK(a.t_s == b.t_s);
		CHECK(glm::length(a.world_from_camera.translation - b.world_from_camera.translation) < 1e-12);
		CHECK(glm::length(a.world_from_camera.rotation - b.world_from_camera.rotation) < 1e-12);
	}

	CHECK(contains(save_tum_trajectory("/nonexistent_dir/x.txt", trajectory), "/nonexistent_dir/x.txt"));
}

TEST_CASE("trajectory: TumTrajectoryWriter's poses and comments read back through load_tum_trajectory") {
	TempFile file("writer_trajectory.txt");
	const std::vector<TimedPose> samples = motion_samples(3.0, 40, 11);
	TumTrajectoryWriter writer;
	REQUIRE(writer.open(file.path.string(), { "tracked by a test", "frames: all" }) == "");
	CHECK(writer.is_open());
	// Every third frame "lost": a comment in place of its pose, as the bench writes them.
	std::vector<TimedPose> written;
	for (size_t i = 0; i < samples.size(); i++) {
		if (i % 3 == 2) {
			REQUIRE(writer.add_comment("lost at " + std::to_string(samples[i].t_s) + ":\ntoo few correspondences") == "");
			continue;
		}
		REQUIRE(writer.add_pose(samples[i]) == "");
		written.push_back(samples[i]);
	}
	// Refused, and the file goes on: a timestamp not after the last, and a non-unit rotation.
	CHECK(contains(writer.add_pose(samples[1]), "is not after"));
	TimedPose bad = samples.back();
	bad.t_s += 1.0;
	bad.world_from_camera.rotation = glm::dquat(2.0, 0.0, 0.0, 0.0);
	CHECK(contains(writer.add_pose(bad), "unit quaternion"));
	REQUIRE(writer.close() == "");

	std::ifstream in(file.path);
	std::string first_line;
	std::getline(in, first_line);
	CHECK(first_line == "# tracked by a test");

	const TrajectoryLoadResult loaded = load_tum_trajectory(file.path.string());
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	REQUIRE(loaded.trajectory.size() == written.size());
	for (size_t i = 0; i < written.size(); i++) {
		CAPTURE(i);
		CHECK(loaded.trajectory.get_samples()[i].t_s == written[i].t_s);
		check_same_pose(loaded.trajectory.get_samples()[i].world_from_camera, written[i].world_from_camera, 1e-15);
	}

	// save_tum_trajectory writes its header the same way.
	Trajectory trajectory;
	std::string error;
	REQUIRE(trajectory.set_samples(written, &error));
	REQUIRE(save_tum_trajectory(file.path.string(), trajectory, { "saved" }) == "");
	const TrajectoryLoadResult saved = load_tum_trajectory(file.path.string());
	REQUIRE_MESSAGE(saved.ok, saved.error);
	CHECK(saved.trajectory.size() == written.size());

	TumTrajectoryWriter unwritable;
	CHECK(contains(unwritable.open("/nonexistent_dir/x.txt"), "/nonexistent_dir/x.txt: cannot be opened for writing"));
	CHECK(contains(unwritable.add_pose(samples[0]), "/nonexistent_dir/x.txt"));
}

TEST_CASE("trajectory: TUM files with comments, blank lines and 4-decimal quaternions load") {
	TempFile file("tum_comments.txt");
	const std::string path = file.write(
			"# ground truth trajectory\n"
			"# timestamp tx ty tz qx qy qz qw\n"
			"\n"
			"1305031102.1753 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\r\n"
			"   1305031102.1853\t1.3303 0.6256 1.6464 0.6579 0.6161 -0.2932 -0.3189  \n"
			"1305031102.1953 1.3160 0.6254 1.6302 0.6609 0.6199 -0.2893 -0.3086\n");
	const TrajectoryLoadResult loaded = load_tum_trajectory(path);
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	REQUIRE(loaded.trajectory.size() == 3);
	const TimedPose &first = loaded.trajectory.get_samples()[0];
	CHECK(first.t_s == 1305031102.1753);
	CHECK(first.world_from_camera.translation == glm::dvec3(1.3405, 0.6266, 1.6575));
	// Read as (qx qy qz qw), normalised.
	const glm::dquat raw(-0.3248, 0.6574, 0.6126, -0.2949);
	CHECK(glm::length(first.world_from_camera.rotation - raw / glm::length(raw)) < 1e-15);
}

TEST_CASE("trajectory: malformed TUM files give an error naming the file and the line") {
	struct Case {
		const char *name;
		const char *text;
		const char *line; // ":<line>:" expected in the error
		const char *hint;
	};
	const Case cases[] = {
		{ "bad_number", "# header\n0.0 0 0 0 0 0 0 1\n0.1 0 0 0.5x 0 0 0 1\n", ":3:", "tz: not a number" },
		{ "seven_fields", "0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n", ":2:", "expected 8 fields" },
		{ "nine_fields", "0.0 0 0 0 0 0 0 1 7\n", ":1:", "expected 8 fields" },
		{ "backwards", "0.0 0 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n\n0.1 0 0 0 0 0 0 1\n", ":4:", "not after" },
		{ "repeated_time", "0.0 0 0 0 0 0 0 1\n0.0 1 0 0 0 0 0 1\n", ":2:", "not after" },
		{ "nan", "0.0 0 0 0 0 0 0 1\n0.1 0 nan 0 0 0 0 1\n", ":2:", "ty: not finite" },
		{ "infinite_time", "inf 0 0 0 0 0 0 1\n", ":1:", "timestamp: not finite" },
		{ "not_unit", "0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 2\n", ":2:", "unit quaternion" },
	};
	for (const Case &c : cases) {
		const std::string case_name = c.name;
		CAPTURE(case_name);
		TempFile file(std::string("tum_") + c.name + ".txt");
		const std::string path = file.write(c.text);
		const TrajectoryLoadResult loaded = load_tum_trajectory(path);
		CHECK_FALSE(loaded.ok);
		CAPTURE(loaded.error);
		CHECK(contains(loaded.error, path + c.line));
		CHECK(contains(loaded.error, c.hint));
		CHECK(loaded.trajectory.is_empty());
	}

	const TrajectoryLoadResult missing = load_tum_trajectory("/nonexistent_dir/poses.txt");
	CHECK_FALSE(missing.ok);
	CHECK(contains(missing.error, "/nonexistent_dir/poses.txt"));

	TempFile empty("tum_empty.txt");
	const TrajectoryLoadResult no_poses = load_tum_trajectory(empty.write("# only a comment\n"));
	CHECK_FALSE(no_poses.ok);
	CHECK(contains(no_poses.error, empty.path.string()));
	CHECK(contains(no_poses.error, "no poses"));
}
