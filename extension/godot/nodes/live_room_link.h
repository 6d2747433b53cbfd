#pragma once
// How RoomProbe's nodes share the one live engine (engine/live_room.h) without each other's
// headers: a node that leads to an engine is a LiveRoomHost (RigCapture owns one; DenseSLAM and
// CoarseRoomModel hand on the one they use), and a node finds its collaborator by NodePath, or,
// with the path left empty, as the one node of that class in its scene.

#include <engine/live_room.h>

#include <rp_godot/godot.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace roomprobe {

class LiveRoomHost {
public:
	virtual ~LiveRoomHost() = default;
	// Null while the host has none (RigCapture always has one).
	virtual std::shared_ptr<LiveRoom> get_live_room() const = 0;
};

// The node p_path leads to when it is set, else the one node of class p_class in p_from's scene
// (the first of several). r_warning says what is wrong, naming p_property: the path leads
// nowhere or to another class, or several candidates were found; empty when all is well, and
// also when nothing was found (the caller knows whether the collaborator is optional).
godot::Node *find_collaborator(const godot::Node &p_from, const godot::NodePath &p_path, const char *p_class, const char *p_property,
		std::string *r_warning);

// The engine behind p_node, when it is a LiveRoomHost that has one.
std::shared_ptr<LiveRoom> live_room_of(godot::Node *p_node);

// Main-thread time of RoomProbe's nodes: each _process, update and signal emission is timed
// with one of these, and the total is what the demo reports per rendered frame. A timer inside
// another (update_now() from _process) adds nothing: the outer one holds its time.
class MainThreadTimer {
public:
	enum Node { RIG_CAPTURE, DENSE_SLAM, COARSE_ROOM_MODEL, ROOM_PROBE, SURFACE_ANCHOR, NODE_COUNT };
	explicit MainThreadTimer(Node p_node);
	~MainThreadTimer();
	MainThreadTimer(const MainThreadTimer &) = delete;
	MainThreadTimer &operator=(const MainThreadTimer &) = delete;
	// Microseconds spent in all timers since the library was loaded: wall-clock time, and the
	// thread's CPU time (less than wall-clock time when the system ran other threads meanwhile).
	static uint64_t total_usec();
	static uint64_t total_cpu_usec();
	// Wall-clock microseconds of one class's nodes; its class name.
	static uint64_t node_usec(Node p_node);
	static const char *node_class(Node p_node);

private:
	Node node;
	bool outermost;
	std::chrono::steady_clock::time_point start;
	uint64_t cpu_start_usec = 0;
};

} // namespace roomprobe
