#pragma once
// What the parts of CoarseRoomModel share (coarse_room_model.cpp, coarse_room_model_found_room.cpp):
// the room search's state, which the node's destructor must see whole. Not for use elsewhere.

#include "coarse_room_model.h"

#include <engine/room_sweep.h>

#include <atomic>
#include <string>
#include <thread>

namespace roomprobe {


// A room search on a recording (find_room_in_recording): the worker writes result, then done.
struct CoarseRoomModel::RoomSearch {
	std::thread thread;
	std::atomic<bool> cancel{ false };
	std::atomic<bool> done{ false };
	std::string recording;
	RoomSweepResult result;
};

} // namespace roomprobe
