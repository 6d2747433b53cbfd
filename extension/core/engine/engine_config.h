#pragma once
// The one way a recording or a rig becomes the engine's configuration: the rig with its
// photometry, the first RGB camera pose, the probes as the points the TSDF evicts last, the ground
// truth, and (when asked) the room. RigCapture, roomprobe_bench, the evaluation and the room sweep
// all start from it and then set what is theirs alone (pose sources, lighting model, ...).

#include "live_room.h"

#include <recording/recording_reader.h>

#include <string>

namespace roomprobe {

// From a rig (a live rig file, or a recording's): p_room is the room file's (null: none; the first
// pose is then the upright one of room_from_sweep.h). The ground truth is cleared. p_take_room:
// also the room's floorplan (has_room follows p_room), else has_room and floorplan stay as they are.
void config_from_rig(const Rig &p_rig, const RigPhotometry &p_photometry, const RoomInfo *p_room, bool p_take_room, LiveRoomConfig *io_config);

// From an open recording: its rig, photometry.yaml (or the rig's photometry), room.yaml and its
// ground-truth RGB-D trajectory. The error (empty on success) names the photometry file's problem.
std::string config_from_recording(const RecordingReader &p_reader, bool p_take_room, LiveRoomConfig *io_config);

} // namespace roomprobe
