#include "room_file.h"

#include <room/floorplan.h> // check_floorplan (room/ is a layer below recording/)

#include "recording_io.h"

#include <rig/trajectory.h>

#include <io/opencv.h>
#include <io/replace_file.h>
#include <io/yaml_fields.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace roomprobe {

namespace {

using recording_io::format_number;

constexpr double WRITE_UNIT_TOLERANCE = 1e-6; // what check_room allows (in memory)
constexpr const char *KEY_VERSION = "roomprobe_room";
constexpr const char *KEY_FLOORPLAN = "floorplan_m";
constexpr const char *KEY_CEILING = "ceiling_height_m";
constexpr const char *KEY_POSE = "initial_rgb_pose";
constexpr const char *KEY_PROBES = "probes";

bool finite(const glm::dvec3 &p_value) {
	return std::isfinite(p_value.x) && std::isfinite(p_value.y) && std::isfinite(p_value.z);
}

bool read_room(YamlFieldReader &p_reader, const cv::FileNode &p_root, RoomInfo *r_room) {
	if (!p_root.isMap()) {
		return p_reader.fail(KEY_VERSION, "missing (the file is not a map of fields; is it a RoomProbe room file?)");
	}
	const cv::FileNode version_node = p_root[KEY_VERSION];
	if (version_node.empty() || version_node.isNone()) {
		return p_reader.fail(KEY_VERSION, "missing (is this a RoomProbe room file?)");
	}
	if (!version_node.isInt()) {
		return p_reader.fail(KEY_VERSION, "must be an integer");
	}
	const int version = int(version_node);
	if (version != ROOM_FILE_VERSION) {
		return p_reader.fail(KEY_VERSION, "unknown version " + std::to_string(version) + " (this build reads version " +
						std::to_string(ROOM_FILE_VERSION) + ")");
	}
	if (!p_reader.check_keys(p_root, "", { KEY_VERSION, KEY_FLOORPLAN, KEY_CEILING, KEY_POSE, KEY_PROBES },
				{ KEY_VERSION, KEY_FLOORPLAN, KEY_CEILING, KEY_POSE })) {
		return false;
	}

	const cv::FileNode floorplan = p_root[KEY_FLOORPLAN];
	if (!floorplan.isSeq()) {
		return p_reader.fail(KEY_FLOORPLAN, "must be a list of [x, z] points");
	}
	RoomInfo room;
	for (size_t i = 0; i < floorplan.size(); i++) {
		double xz[2];
		if (!p_reader.numbers(floorplan[int(i)], std::string(KEY_FLOORPLAN) + "[" + std::to_string(i) + "]", 2, xz)) {
			return false;
		}
		room.floorplan.points.push_back(Vec2{ xz[0], xz[1] });
	}
	if (!p_reader.number(p_root[KEY_CEILING], KEY_CEILING, &room.floorplan.ceiling_height_m)) {
		return false;
	}

	const cv::FileNode pose = p_root[KEY_POSE];
	const std::string pose_prefix = std::string(KEY_POSE) + ".";
	if (!pose.isMap()) {
		return p_reader.fail(KEY_POSE, "must be a map with rotation_xyzw and translation_m");
	}
	double q[4];
	double t[3];
	if (!p_reader.check_keys(pose, pose_prefix, { "rotation_xyzw", "translation_m" }) ||
			!p_reader.numbers(pose["rotation_xyzw"], pose_prefix + "rotation_xyzw", 4, q) ||
			!p_reader.numbers(pose["translation_m"], pose_prefix + "translation_m", 3, t)) {
		return false;
	}
	const glm::dquat rotation(q[3], q[0], q[1], q[2]); // glm's constructor takes (w, x, y, z)
	const double norm = glm::length(rotation);
	// A hand-written file may round its quaternion (as TUM files do): normalised, like theirs.
	if (!(std::abs(norm - 1.0) <= TUM_UNIT_TOLERANCE)) {
		return p_reader.fail(pose_prefix + "rotation_xyzw", "not a unit quaternion (norm " + format_number(norm) + ", allowed 1 +- " +
						format_number(TUM_UNIT_TOLERANCE) + ")");
	}
	room.initial_rgb_pose.rotation = rotation / norm;
	room.initial_rgb_pose.translation = glm::dvec3(t[0], t[1], t[2]);

	const cv::FileNode probes = p_root[KEY_PROBES];
	if (!probes.empty() && !probes.isNone()) {
		if (!probes.isSeq()) {
			return p_reader.fail(KEY_PROBES, "must be a list of [x, y, z] positions");
		}
		for (size_t i = 0; i < probes.size(); i++) {
			double xyz[3];
			if (!p_reader.numbers(probes[int(i)], std::string(KEY_PROBES) + "[" + std::to_string(i) + "]", 3, xyz)) {
				return false;
			}
			room.probes.emplace_back(xyz[0], xyz[1], xyz[2]);
		}
	}
	const std::string problem = check_room(room);
	if (!problem.empty()) {
		p_reader.error = problem;
		return false;
	}
	*r_room = room;
	return true;
}

} // namespace

std::string check_room(const RoomInfo &p_room) {
	const FloorplanCheck check = check_floorplan(p_room.floorplan);
	if (!check.ok) {
		const bool ceiling = check.problem == FloorplanCheck::Problem::CeilingNotPositive;
		return std::string(ceiling ? KEY_CEILING : KEY_FLOORPLAN) + ": " + floorplan_problem_summary(check.problem) + ": " + check.message;
	}
	const glm::dquat &q = p_room.initial_rgb_pose.rotation;
	if (!(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w))) {
		return std::string(KEY_POSE) + ".rotation_xyzw: must be finite";
	}
	if (!(std::abs(glm::length(q) - 1.0) <= WRITE_UNIT_TOLERANCE)) {
		return std::string(KEY_POSE) + ".rotation_xyzw: not a unit quaternion (norm " + format_number(glm::length(q)) + ")";
	}
	if (!finite(p_room.initial_rgb_pose.translation)) {
		return std::string(KEY_POSE) + ".translation_m: must be finite";
	}
	for (size_t i = 0; i < p_room.probes.size(); i++) {
		if (!finite(p_room.probes[i])) {
			return std::string(KEY_PROBES) + "[" + std::to_string(i) + "]: must be finite";
		}
	}
	return std::string();
}

RoomLoadResult load_room_file(const std::string &p_path) {
	RoomLoadResult result;
	std::error_code ec;
	if (!std::filesystem::is_regular_file(p_path, ec)) {
		result.error = recording_io::not_a_file_error(p_path);
		return result;
	}
	// Read here and parsed from memory, as the rig file: the text is screened first.
	std::string text;
	{
		std::ifstream file(p_path, std::ios::binary);
		std::stringstream bytes;
		bytes << file.rdbuf();
		text = bytes.str();
		if (!file || text.empty()) {
			result.error = p_path + ": cannot read the room file (empty or unreadable)";
			return result;
		}
	}
	const std::string malformed = check_yaml_text(text);
	if (!malformed.empty()) {
		result.error = p_path + ": " + malformed;
		return result;
	}
	YamlFieldReader reader(YamlFieldReader::NonFinite::Refuse);
	RoomInfo room;
	try {
		cv::FileStorage storage(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
		if (!storage.isOpened()) {
			result.error = p_path + ": cannot open the room file";
			return result;
		}
		if (!read_room(reader, storage.root(), &room)) {
			result.error = p_path + ": " + reader.error;
			return result;
		}
	} catch (const cv::Exception &e) {
		result.error = p_path + ": malformed YAML: " + describe_yaml_parse_error(e);
		return result;
	} catch (const std::exception &e) {
		result.error = p_path + ": " + e.what();
		return result;
	}
	result.room = room;
	result.ok = true;
	return result;
}

namespace {

// The room as YAML text, built in memory so the file is written whole (io/replace_file.h).
std::string room_yaml(const RoomInfo &p_room) {
	const glm::dquat q = glm::normalize(p_room.initial_rgb_pose.rotation);
	const glm::dvec3 &t = p_room.initial_rgb_pose.translation;
	cv::FileStorage storage(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
	storage.writeComment(" RoomProbe room; the fields are described in docs/recording-format.md.");
	storage << KEY_VERSION << ROOM_FILE_VERSION;
	storage.writeComment(" Floorplan corners [x, z], metres, on the floor (world y = 0); the room is this polygon extruded to the ceiling.");
	storage << KEY_FLOORPLAN << "[";
	for (const Vec2 &point : p_room.floorplan.points) {
		storage << "[:" << point.x << point.y << "]";
	}
	storage << "]";
	storage << KEY_CEILING << p_room.floorplan.ceiling_height_m;
	storage.writeComment(" world_from_rgb at the first RGB-D frame (world: Y up, metres; camera: x right, y down, z forward).");
	storage << KEY_POSE << "{";
	storage << "rotation_xyzw" << "[:" << q.x << q.y << q.z << q.w << "]";
	storage << "translation_m" << "[:" << t.x << t.y << t.z << "]";
	storage << "}";
	if (!p_room.probes.empty()) {
		storage.writeComment(" Probe positions [x, y, z], world metres; groundtruth/cubemaps.txt refers to them by index.");
		storage << KEY_PROBES << "[";
		for (const glm::dvec3 &probe : p_room.probes) {
			storage << "[:" << probe.x << probe.y << probe.z << "]";
		}
		storage << "]";
	}
	return storage.releaseAndGetString();
}

} // namespace

std::string save_room_file(const std::string &p_path, const RoomInfo &p_room) {
	const std::string problem = check_room(p_room);
	if (!problem.empty()) {
		return p_path + ": " + problem;
	}
	std::string text;
	try {
		text = room_yaml(p_room);
	} catch (const cv::Exception &e) {
		return p_path + ": cannot write: " + e.err;
	} catch (const std::exception &e) {
		return p_path + ": cannot write: " + e.what();
	}
	return replace_file(p_path, text.data(), text.size());
}

} // namespace roomprobe
