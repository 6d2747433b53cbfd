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

// From an open recording: its rig, room.yaml and its ground-truth RGB-D trajectory, with
// p_photometry (read_recording_photometry's, or none where the frames are taken as recorded).
void config_from_recording(const RecordingReader &p_reader, const RigPhotometry &p_photometry, bool p_take_room, LiveRoomConfig *io_config);
// The same with the recording's own photometry (read_recording_photometry: synth.yaml's, else the
// rig's). The error (empty on success) names the photometry file's problem.
std::string config_from_recording(const RecordingReader &p_reader, bool p_take_room, LiveRoomConfig *io_config);

} // namespace roomprobe
