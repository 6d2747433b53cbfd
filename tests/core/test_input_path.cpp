// io/input_path (issue #38): an input path is looked at before it is read, and the message says
// what is wrong with it. /dev/zero given as a panorama was once called "no such file"; a named pipe
// would have blocked the reader. Checked through the loaders that use it.
#include "envmap/export.h"
#include "io/input_path.h"
#include "io/yaml_fields.h"
#include "recording/recording_reader.h"
#include "recording/room_file.h"
#include "recording/tum_dataset.h"
#include "rig/rig.h"
#include "synth/synth_scene.h"

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

struct Scratch {
	fs::path path = fs::temp_directory_path() / ("roomprobe_input_path_" + std::to_string(::getpid()));
	Scratch() {
		fs::remove_all(path);
		fs::create_directories(path);
	}
	~Scratch() {
		std::error_code ec;
		fs::remove_all(path, ec);
	}
	std::string at(const std::string &p_name) const { return (path / p_name).string(); }
};

} // namespace

TEST_CASE("input paths: a device, a pipe, a folder, a dangling link and a missing file are each named for what they are") {
	const Scratch scratch;
	std::ofstream(scratch.at("file.txt")) << "text";
	REQUIRE(::mkfifo(scratch.at("pipe").c_str(), 0600) == 0);
	fs::create_symlink(scratch.at("gone.txt"), scratch.at("dangling"));
	fs::create_symlink(scratch.at("file.txt"), scratch.at("link"));

	CHECK(input_file_problem(scratch.at("file.txt")) == "");
	CHECK(input_file_problem(scratch.at("link")) == ""); // through links
	CHECK(input_file_problem("/dev/zero") == "/dev/zero: not a regular file (a character device)");
	CHECK(input_file_problem(scratch.at("pipe")) == scratch.at("pipe") + ": not a regular file (a named pipe (FIFO))");
	CHECK(input_file_problem(scratch.path.string()) == scratch.path.string() + ": a folder, not a file");
	CHECK(input_file_problem(scratch.at("none")) == scratch.at("none") + ": missing");
	CHECK(input_file_problem(scratch.at("none"), "no such rig file") == scratch.at("none") + ": no such rig file");
	CHECK(input_file_problem(scratch.at("dangling")) == scratch.at("dangling") + ": a link to a missing file (" + scratch.at("gone.txt") + ")");
	CHECK(input_file_problem(scratch.at("file.txt/under")) == scratch.at("file.txt/under") + ": missing");

	CHECK(input_folder_problem(scratch.path.string()) == "");
	CHECK(input_folder_problem("/dev/zero") == "/dev/zero: not a folder (a character device)");
	CHECK(input_folder_problem(scratch.at("file.txt")) == scratch.at("file.txt") + ": not a folder (a regular file)");
	CHECK(input_folder_problem(scratch.at("none"), "no such recording folder") == scratch.at("none") + ": no such recording folder");

	CHECK(describe_path("/dev/zero") == "a character device");
	CHECK(describe_path(scratch.at("pipe")) == "a named pipe (FIFO)");
	CHECK(describe_path(scratch.at("none")) == "missing");
}

TEST_CASE("input paths: every loader a user's path reaches names a device for what it is, and a pipe never blocks") {
	const Scratch scratch;
	REQUIRE(::mkfifo(scratch.at("pipe").c_str(), 0600) == 0);
	for (const std::string &device : { std::string("/dev/zero"), scratch.at("pipe") }) {
		CAPTURE(device);
		const std::string what = device == "/dev/zero" ? "a character device" : "a named pipe (FIFO)";
		CHECK(contains(synth::load_panorama(device).error, device + ": not a regular file (" + what + "), so the panorama cannot be read"));
		CHECK(contains(load_rig(device).error, device + ": not a regular file (" + what + ")"));
		CHECK(contains(load_room_file(device).error, device + ": not a regular file (" + what + ")"));
		cv::FileStorage storage;
		CHECK(contains(open_yaml_file(device, &storage), device + ": not a regular file (" + what + ")"));
		Cubemap cubemap;
		CHECK(contains(read_cubemap_exr(device, &cubemap), device + ": not a regular file (" + what + ")"));
		RecordingReader reader;
		CHECK(contains(reader.open(device).error, device + ": not a folder (" + what + ")"));
		CHECK(contains(open_tum_dataset(device, &reader, TumDatasetOptions()).error, device + ": not a folder (" + what + ")"));
	}
	// A missing panorama keeps its words (it was "no such file" for a device too).
	CHECK(contains(synth::load_panorama(scratch.at("sky.hdr")).error, scratch.at("sky.hdr") + ": no such file, so the panorama cannot be read"));
	RecordingReader reader;
	CHECK(contains(reader.open(scratch.at("none")).error, "no such recording folder"));
}
