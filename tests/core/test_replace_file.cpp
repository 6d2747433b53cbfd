// io/replace_file (issue #38): an output file is replaced whole or left as it was, and a folder or a
// device in its place is refused, never removed (roomprobe_room --picture /dev/full --force once
// deleted /dev/full). Checked through the writers that use it: png_write, the cubemap EXR, the room
// file, the rig file and the TUM trajectory writer.
#include "envmap/export.h"
#include "io/image_codec.h"
#include "io/replace_file.h"
#include "recording/room_file.h"
#include "rig/trajectory.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/resource.h>
#include <unistd.h>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

struct Folder {
	fs::path path;
	explicit Folder(const std::string &p_name) :
			path(fs::temp_directory_path() / ("roomprobe_replace_" + p_name + "_" + std::to_string(::getpid()))) {
		fs::remove_all(path);
		fs::create_directories(path);
	}
	~Folder() {
		std::error_code ec;
		fs::remove_all(path, ec);
	}
	std::string write(const std::string &p_name, const std::string &p_text) const {
		std::ofstream((path / p_name).string()) << p_text;
		return (path / p_name).string();
	}
	std::string read(const std::string &p_name) const {
		std::ifstream file((path / p_name).string());
		return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
	}
	// What the folder holds: a temporary file left behind shows here.
	size_t entries() const {
		return size_t(std::distance(fs::directory_iterator(path), fs::directory_iterator()));
	}
};

// While it lives, no file may grow past p_bytes: a write beyond fails with EFBIG ("File too
// large"), a full disk without mounting one. SIGXFSZ, which would end the process, is ignored.
// No doctest check may run meanwhile (its output could be such a file).
struct FileSizeLimit {
	rlimit saved{};
	void (*saved_handler)(int) = SIG_DFL;
	explicit FileSizeLimit(rlim_t p_bytes) {
		::getrlimit(RLIMIT_FSIZE, &saved);
		saved_handler = std::signal(SIGXFSZ, SIG_IGN);
		rlimit limit = saved;
		limit.rlim_cur = p_bytes;
		::setrlimit(RLIMIT_FSIZE, &limit);
	}
	~FileSizeLimit() {
		::setrlimit(RLIMIT_FSIZE, &saved);
		std::signal(SIGXFSZ, saved_handler);
	}
};

cv::Mat noise_image() { // PNG cannot squeeze it under the limits below
	cv::Mat image(64, 64, CV_8UC3);
	cv::RNG(3).fill(image, cv::RNG::UNIFORM, 0, 256);
	return image;
}

Cubemap noise_cubemap() {
	Cubemap cubemap = make_cubemap(16);
	for (cv::Mat &face : cubemap.faces) {
		cv::RNG(5).fill(face, cv::RNG::UNIFORM, 0.0, 1.0);
	}
	return cubemap;
}

RoomInfo a_room() {
	RoomInfo room;
	room.floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 5.0 }, { 0.0, 5.0 } };
	room.floorplan.ceiling_height_m = 2.5;
	room.initial_rgb_pose.translation = glm::dvec3(1.0, 1.5, 2.0);
	return room;
}

// A few poses, many more bytes than the limits below.
std::string write_trajectory(const std::string &p_path) {
	TumTrajectoryWriter writer;
	std::string error = writer.open(p_path, { "written by a test" });
	for (int i = 0; error.empty() && i < 20; i++) {
		TimedPose pose;
		pose.t_s = 1.0 + 0.1 * i;
		pose.world_from_camera.translation = glm::dvec3(0.01 * i, 0.0, 0.0);
		error = writer.add_pose(pose);
	}
	const std::string closed = writer.close();
	return error.empty() ? closed : error;
}

} // namespace

TEST_CASE("output files: a file is replaced whole (through a link too) and no temporary file is left") {
	const Folder folder("whole");
	const std::string map = folder.write("map.png", "the old map");
	const cv::Mat image = noise_image();
	REQUIRE(png_write(map, image) == "");
	cv::Mat back;
	REQUIRE(image_read(map, ImageReadMode::Unchanged, &back) == "");
	CHECK(cv::norm(back, image, cv::NORM_INF) == 0.0);
	CHECK(folder.entries() == 1);

	// Through a link the file it names is replaced; the link stays a link.
	fs::create_symlink(map, folder.path / "link.png");
	const cv::Mat other = noise_image() / 2;
	REQUIRE(png_write((folder.path / "link.png").string(), other) == "");
	CHECK(fs::is_symlink(folder.path / "link.png"));
	REQUIRE(image_read(map, ImageReadMode::Unchanged, &back) == "");
	CHECK(cv::norm(back, other, cv::NORM_INF) == 0.0);
	CHECK(folder.entries() == 2);

	// A replacement never committed leaves the target as it was, and nothing beside it.
	const std::string text = folder.write("text.txt", "kept");
	{
		FileReplacement replacement;
		REQUIRE(replacement.begin(text) == "");
		CHECK(fs::path(replacement.temp_path()).parent_path() == folder.path);
		CHECK(fs::exists(replacement.temp_path()));
		std::ofstream(replacement.temp_path()) << "half writ";
	}
	CHECK(folder.read("text.txt") == "kept");
	CHECK(folder.entries() == 3);
	CHECK(write_trajectory(text) == "");
	CHECK(load_tum_trajectory(text).ok);
	CHECK(folder.entries() == 3);
}

TEST_CASE("output files: a write that fails part-way (a file size limit stands for a full disk) keeps the old file and leaves no temporary file") {
	const Folder folder("failed");
	const std::string names[6] = { "map.png", "map.exr", "room.yaml", "trajectory.txt", "bytes.bin", "rig.yaml" };
	for (const std::string &name : names) {
		folder.write(name, "the old " + name);
	}
	const auto at = [&](int p_index) { return (folder.path / names[p_index]).string(); };
	const std::string bytes(4096, 'x');
	std::string errors[6];
	{
		const FileSizeLimit limit(64);
		errors[0] = png_write(at(0), noise_image());
		errors[1] = write_cubemap_exr(at(1), noise_cubemap());
		errors[2] = save_room_file(at(2), a_room());
		errors[3] = write_trajectory(at(3));
		errors[4] = replace_file(at(4), bytes.data(), bytes.size());
		errors[5] = save_rig(at(5), test_rig());
	}
	for (int i = 0; i < 6; i++) {
		CAPTURE(errors[i]);
		CHECK(contains(errors[i], at(i) + ": "));
		CHECK(folder.read(names[i]) == "the old " + names[i]);
	}
	CHECK(contains(errors[0], "File too large"));
	CHECK(contains(errors[4], "could not be written: File too large"));
	CHECK(folder.entries() == 6);
}

TEST_CASE("output files: a folder or a device in the file's place is refused and never removed" * doctest::skip(!fs::exists("/dev/full"))) {
	const Folder folder("device");
	CHECK(contains(check_replaceable("/dev/full"), "/dev/full: is not a regular file"));
	CHECK(check_replaceable((folder.path / "absent.png").string()) == "");
	// A link to /dev/full, not /dev/full itself: were it removed, only the test's own link would go.
	const std::string device = (folder.path / "full.png").string();
	fs::create_symlink("/dev/full", device);
	const std::string errors[4] = { png_write(device, noise_image()), write_cubemap_exr(device, noise_cubemap()), save_room_file(device, a_room()),
		write_trajectory(device) };
	for (const std::string &error : errors) {
		CHECK(contains(error, device + ": is not a regular file"));
	}
	CHECK(fs::is_symlink(device));
	CHECK(fs::is_character_file("/dev/full"));

	fs::create_directory(folder.path / "maps");
	CHECK(contains(png_write((folder.path / "maps").string(), noise_image()), "is a folder, not a file"));
	CHECK(fs::is_directory(folder.path / "maps"));
	CHECK(folder.entries() == 2);
}
