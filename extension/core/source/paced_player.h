#pragma once
// PacedPlayer: a recording played in real time on its own thread, as a device would deliver it:
// each frame is read when its time comes and handed to a sink (the engine's push_*). The clock is
// either the wall clock (times a speed: roomprobe_bench live) or one the owner advances (Godot's
// frame delta: RigCapture), and a reader slower than the clock drops frames by a DropPolicy. The
// same object steps one frame at a time when no thread runs (RigCapture's Step pacing).
//
// One lock guards the position and the clock; frames are read and sunk outside it.

#include "recording_player.h"

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace roomprobe {

enum class PaceClock {
	Manual, // advance() moves it (the owner's frame clock)
	Wall, // steady_clock since start(), times speed
};

struct PacedOptions {
	PaceClock clock = PaceClock::Manual;
	double speed = 1.0; // Wall: recording seconds per second, held to [0.001, 1e6]
	DropPolicy drop = DropPolicy::KeepNewest;
	std::function<void()> on_end; // called on the thread when the last frame has been sunk
};

class PacedPlayer {
public:
	using Sink = std::function<void(SourceFrame &&)>;

	PacedPlayer() = default;
	explicit PacedPlayer(RecordingPlayer p_player) :
			player(std::move(p_player)) {}
	~PacedPlayer() { stop(); }
	PacedPlayer(const PacedPlayer &) = delete;
	PacedPlayer &operator=(const PacedPlayer &) = delete;

	// Replaces the recording (stopping the thread first) and rewinds.
	void open(RecordingPlayer p_player);
	bool is_open() const { return player.is_open(); }
	const RecordingPlayer &recording() const { return player; } // its events and reader

	// Starts the thread at the current position and clock. Frames go to p_sink, in time order.
	void start(const PacedOptions &p_options, Sink p_sink);
	void stop(); // joins; frames being read are sunk first. From the sink itself: stops without joining
	bool is_running() const { return thread.joinable(); }

	void advance(double p_delta_s); // Manual clock
	void rewind(); // position and clock to the start, drop count 0
	bool reached_end() const;
	size_t dropped() const;
	double clock_s() const;

	// No thread running: reads the next frame, sets the clock to its time and moves on. At the
	// end: ok false, error "end"; while the thread runs: ok false, error "running". p_loop: at the
	// end, rewinds first.
	SourceFrame step(bool p_loop = false);
	bool at_end() const;
	size_t position() const; // the next event to read (thread-safe)

private:
	void run();
	double elapsed_locked() const;

	RecordingPlayer player;
	PacedOptions options;
	Sink sink;
	mutable std::mutex mutex;
	std::condition_variable wake;
	std::thread thread;
	bool stopping = false;
	bool running = false; // a thread runs (start() .. stop())
	bool end_reached = false;
	double clock = 0.0; // Manual: recording seconds since the first event
	std::chrono::steady_clock::time_point wall_start; // Wall: when the clock was at 0
	size_t dropped_count = 0;
	uint64_t pass = 0; // counts rewinds and opens: a batch read before one is not sunk after it
};

} // namespace roomprobe
