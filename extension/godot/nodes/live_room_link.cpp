#include "live_room_link.h"

#include <atomic>
#include <ctime>

using namespace godot;

namespace roomprobe {

namespace {

// Only the main thread times, but atomics keep a stray call from another thread harmless.
std::atomic<uint64_t> main_thread_usec{ 0 };
std::atomic<uint64_t> main_thread_cpu_usec{ 0 };
std::atomic<uint64_t> node_usecs[MainThreadTimer::NODE_COUNT];
thread_local int timer_depth = 0;

uint64_t thread_cpu_usec() {
	timespec now{};
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
	return uint64_t(now.tv_sec) * 1000000u + uint64_t(now.tv_nsec) / 1000u;
}

} // namespace

MainThreadTimer::MainThreadTimer(Node p_node) :
		node(p_node), outermost(timer_depth++ == 0), start(std::chrono::steady_clock::now()) {
	if (outermost) {
		cpu_start_usec = thread_cpu_usec();
	}
}

MainThreadTimer::~MainThreadTimer() {
	timer_depth--;
	if (!outermost) {
		return;
	}
	const uint64_t usec = uint64_t(std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count());
	main_thread_usec += usec;
	node_usecs[node] += usec;
	main_thread_cpu_usec += thread_cpu_usec() - cpu_start_usec;
}

uint64_t MainThreadTimer::total_usec() { return main_thread_usec.load(); }

uint64_t MainThreadTimer::total_cpu_usec() { return main_thread_cpu_usec.load(); }

uint64_t MainThreadTimer::node_usec(Node p_node) { return node_usecs[p_node].load(); }

const char *MainThreadTimer::node_class(Node p_node) {
	static const char *const names[NODE_COUNT] = { "RigCapture", "DenseSLAM", "CoarseRoomModel", "RoomProbe", "SurfaceAnchor" };
	return names[p_node];
}

Node *find_collaborator(const Node &p_from, const NodePath &p_path, const char *p_class, const char *p_property, std::string *r_warning) {
	r_warning->clear();
	if (!p_from.is_inside_tree()) {
		return nullptr;
	}
	if (!p_path.is_empty()) {
		Node *node = p_from.get_node_or_null(p_path);
		if (node == nullptr || !node->is_class(p_class)) {
			*r_warning = std::string(p_property) + " does not lead to a " + p_class + " node.";
			return nullptr;
		}
		return node;
	}
	// The scene: the topmost ancestor below the tree's root.
	const Node *top = &p_from;
	while (top->get_parent() != nullptr && top->get_parent()->get_parent() != nullptr) {
		top = top->get_parent();
	}
	Array found = top->find_children("*", p_class, true, false);
	if (top->is_class(p_class)) {
		found.push_front(Variant(top));
	}
	if (found.size() == 0) {
		return nullptr;
	}
	Node *first = cast_to<Node>(found.get(0).get_object());
	if (found.size() > 1 && first != nullptr) {
		*r_warning = std::string(p_property) + " is empty and the scene has " + std::to_string(found.size()) + " " + p_class +
				" nodes: the first is used. Set " + p_property + " to choose.";
	}
	return first;
}

std::shared_ptr<LiveRoom> live_room_of(Node *p_node) {
	const LiveRoomHost *host = dynamic_cast<const LiveRoomHost *>(p_node);
	return host != nullptr ? host->get_live_room() : nullptr;
}

} // namespace roomprobe
