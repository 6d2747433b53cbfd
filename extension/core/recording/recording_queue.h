#pragma once
// RecordingQueue: records live streams without holding up their capture threads. push_* copy a
// frame into a bounded queue and return; one writer thread encodes and writes them with
// RecordingWriter (PNG/EXR and index lines, flushed, so a crash keeps everything up to the last
// frame). When the disk is slower than the cameras, the frames that do not fit are not written:
// each run of them is a gap, counted and written to gaps.txt (docs/recording-format.md), so
// nothing is lost silently. A folder that holds anything is never written into.

#include "recording_writer.h"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

namespace roomprobe {

struct RecordingQueueOptions {
	size_t max_queued_frames = 90; // both streams together; about 3 s of RGB-D at 30 Hz (80 MiB at 640x480)
	RecordingWriteOptions write; // allow_non_empty_folder is refused here: a live session never overwrites
};

// Where a recording stands; a copy, safe from any thread.
struct RecordingQueueStatus {
	bool recording = false; // between a successful open() and close()
	std::string folder;
	uint64_t written[2] = { 0, 0 }; // frames written, indexed by RecordingStream
	uint64_t dropped[2] = { 0, 0 }; // frames left out because the queue was full
	uint64_t gaps = 0; // runs of dropped frames (lines of gaps.txt)
	size_t queued = 0; // frames waiting for the writer
	double seconds = 0.0; // since open()
	double megabytes_written = 0.0; // image bytes on disk (MB = 1e6 bytes)
	double megabytes_per_s = 0.0; // over the whole recording
	std::string error; // the first write error; the recording stops taking frames after it
};

class RecordingQueue {
public:
	RecordingQueue() = default;
	~RecordingQueue(); // close()
	RecordingQueue(const RecordingQueue &) = delete;
	RecordingQueue &operator=(const RecordingQueue &) = delete;

	// Starts a recording in p_folder (created if missing; refused if it holds anything), with or
	// without a room. Starts the writer thread.
	RecordingStatus open(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingQueueOptions &p_options = RecordingQueueOptions());
	bool is_open() const;

	// Queue a frame (copied). False when it was dropped: not recording, a write error, or the
	// queue full (then counted in a gap). Any thread.
	bool push_rgbd(const RgbdFrame &p_frame);
	bool push_fisheye(const FisheyeFrame &p_frame);

	// Writes what is queued, then gaps.txt, and closes. The first error of the whole recording.
	RecordingStatus close();

	RecordingQueueStatus status() const;

private:
	struct Item {
		RecordingStream stream = RecordingStream::Rgbd;
		RgbdFrame rgbd;
		FisheyeFrame fisheye;
	};
	struct Gap {
		RecordingStream stream = RecordingStream::Rgbd;
		double first_s = 0.0; // timestamps of the first and last frame left out
		double last_s = 0.0;
		uint64_t frames = 0;
	};
	bool push(Item &&p_item, double p_timestamp_s);
	void run();
	std::string write_gaps() const;

	mutable std::mutex mutex;
	std::condition_variable wake;
	std::thread writer_thread;
	bool closing = false;
	std::deque<Item> queue;
	std::vector<Gap> gaps;
	static constexpr size_t NO_GAP = size_t(-1);
	size_t open_gap[2] = { NO_GAP, NO_GAP }; // per stream: the gap its last frame was dropped into, if it was
	RecordingQueueStatus current;
	double started_s = 0.0; // steady clock, seconds
	RecordingQueueOptions options;
	RecordingWriter writer; // the writer thread's while it runs
};

} // namespace roomprobe
