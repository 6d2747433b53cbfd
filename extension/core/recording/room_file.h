#pragma once
// A recording's room.yaml: the floorplan, the ceiling height, the RGB-D camera's pose at the
// first frame and the probe positions (docs/recording-format.md, "room.yaml"). YAML through
// cv::FileStorage, strict like the rig file: every field once, unknown fields are errors.

#include "recording_types.h"

#include <string>

namespace roomprobe {

// The version of the schema load_room_file reads and save_room_file writes (roomprobe_room).
inline constexpr int ROOM_FILE_VERSION = 1;

struct RoomLoadResult {
	bool ok = false;
	std::string error; // names the file and the field: "rec/room.yaml: floorplan_m[2]: must be a list of 2 numbers"
	RoomInfo room;
};

// Checks a room: the floorplan passes check_floorplan(), the initial pose is finite with a
// unit rotation (within 1e-6), probe positions are finite. "" or "field: problem".
std::string check_room(const RoomInfo &p_room);

RoomLoadResult load_room_file(const std::string &p_path);
// Returns "" or the error naming the file; never writes a room that load_room_file would refuse.
// Replaces p_path whole or leaves it as it was (io/replace_file.h): a folder or a device is refused.
std::string save_room_file(const std::string &p_path, const RoomInfo &p_room);

} // namespace roomprobe
