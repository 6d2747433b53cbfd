#pragma once
// RecordingPlayer: the one way a recording's frames come out, in time order, for every caller that
// plays one (RigCapture, roomprobe_bench, the evaluation, the room sweep). It owns nothing but a
// position in the reader's event list; reading is const, so a capture thread may read while the
// owner keeps the position under its own lock (PacedPlayer does).
//
// Two ways to play:
//   step: next() reads the next event's frame; take_until() hands out the events up to a time
//     (the evaluation feeds everything before each true cubemap);
//   paced: take_due() hands out the events due at a clock, and with DropPolicy::KeepNewest only the
//     newest of each stream among them (a slow reader drops frames instead of falling behind).

#include <recording/recording_reader.h>

#include <memory>
#include <string>
#include <vector>

namespace roomprobe {

struct PlayerOptions {
	double max_seconds = 0.0; // play only the events this long after the recording's first, of either stream (0: all)
	size_t max_rgbd_frames = 0; // stop before the RGB-D event after this many played (0: all; no limit when rgbd is false)
	bool rgbd = true, fisheye = true; // the streams played (the others' events are left out)
};

enum class DropPolicy {
	None, // every due event is handed out
	KeepNewest, // of the due events, only the newest of each stream; the rest count as dropped
};

// One event's frame as read: which event, and the frame or why not.
struct SourceFrame {
	PlaybackEvent event;
	bool ok = false;
	std::string error; // names the image file
	RgbdFrame rgbd; // stream Rgbd
	FisheyeFrame fisheye; // stream Fisheye
	double read_ms = 0.0; // reading and decoding it
	double late_ms = 0.0; // paced on the wall clock: how long after its time it began to be read
};

class RecordingPlayer {
public:
	RecordingPlayer() = default;
	RecordingPlayer(std::shared_ptr<const RecordingReader> p_reader, const PlayerOptions &p_options = PlayerOptions());

	bool is_open() const { return reader_ != nullptr; }
	const RecordingReader &reader() const { return *reader_; }
	const std::shared_ptr<const RecordingReader> &shared_reader() const { return reader_; }
	// The events played (PlayerOptions applied), and the time of the first (the clock's zero).
	const std::vector<PlaybackEvent> &events() const { return events_; }
	double start_s() const { return events_.empty() ? 0.0 : events_.front().time_s; }
	size_t rgbd_events() const { return rgbd_events_; }

	size_t position() const { return next_; }
	bool at_end() const { return next_ >= events_.size(); }
	void rewind() { next_ = 0; }
	// The next event's time since the first (at_end: none).
	double next_due_s() const { return at_end() ? 0.0 : events_[next_].time_s - start_s(); }

	// Reads event p_event's frame (thread-safe: the reader is const).
	SourceFrame read(size_t p_event) const;
	// Step: reads the next event's frame and moves on. At the end: ok false, error "end".
	SourceFrame next();
	// The next event's index, moving past it without reading (not at_end()).
	size_t take_next() { return next_++; }
	// The events (indices into events()) at or before p_time_s on the recording's clock, and moves
	// past them.
	std::vector<size_t> take_until(double p_time_s);
	// The events due p_elapsed_s after the first, and moves past them. KeepNewest drops all but
	// the newest of each stream and adds their count to *r_dropped (may be null).
	std::vector<size_t> take_due(double p_elapsed_s, DropPolicy p_drop, size_t *r_dropped);

private:
	std::shared_ptr<const RecordingReader> reader_;
	std::vector<PlaybackEvent> events_;
	size_t rgbd_events_ = 0;
	size_t next_ = 0;
};

// Opens p_folder into a player: the error (empty on success) names the recording's problem.
std::string open_player(const std::string &p_folder, const PlayerOptions &p_options, RecordingPlayer *r_player);

} // namespace roomprobe
