#include "recording_queue.h"

#include "recording_io.h"

#include <chrono>
#include <cmath>
#include <fstream>

namespace roomprobe {

namespace {

double steady_s() {
	return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

RecordingStatus failed(std::string p_error) {
	RecordingStatus status;
	status.error = std::move(p_error);
	return status;
}

} // namespace

RecordingQueue::~RecordingQueue() {
	close();
}

RecordingStatus RecordingQueue::open(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingQueueOptions &p_options) {
	if (is_open()) {
		return failed(p_folder + ": a recording is already running into " + status().folder + "; stop it first");
	}
	if (p_options.max_queued_frames < 1 || p_options.max_queued_frames > 100000) {
		return failed(p_folder + ": max_queued_frames = " + std::to_string(p_options.max_queued_frames) + " must be within 1 to 100000");
	}
	RecordingWriteOptions write = p_options.write;
	write.allow_non_empty_folder = false; // a live session never writes over anything
	const RecordingStatus opened = p_room ? writer.open(p_folder, p_rig, *p_room, write) : writer.open_without_room(p_folder, p_rig, write);
	if (!opened.ok) {
		return opened;
	}
	std::lock_guard lock(mutex);
	options = p_options;
	queue.clear();
	gaps.clear();
	open_gap[0] = open_gap[1] = NO_GAP;
	closing = false;
	current = RecordingQueueStatus();
	current.recording = true;
	current.folder = p_folder;
	started_s = steady_s();
	writer_thread = std::thread([this] { run(); });
	RecordingStatus ok;
	ok.ok = true;
	return ok;
}

bool RecordingQueue::is_open() const {
	std::lock_guard lock(mutex);
	return current.recording;
}

bool RecordingQueue::push_rgbd(const RgbdFrame &p_frame) {
	Item item;
	item.stream = RecordingStream::Rgbd;
	item.rgbd = p_frame; // every field; then pixels of its own
	item.rgbd.rgb = p_frame.rgb.clone();
	item.rgbd.depth_m = p_frame.depth_m.clone();
	return push(std::move(item), p_frame.timestamp_s);
}

bool RecordingQueue::push_fisheye(const FisheyeFrame &p_frame) {
	Item item;
	item.stream = RecordingStream::Fisheye;
	item.fisheye = p_frame;
	item.fisheye.image = p_frame.image.clone();
	return push(std::move(item), p_frame.timestamp_s);
}

bool RecordingQueue::push(Item &&p_item, double p_timestamp_s) {
	{
		std::lock_guard lock(mutex);
		if (!current.recording || closing || !current.error.empty()) {
			return false;
		}
		const int stream = int(p_item.stream);
		if (queue.size() >= options.max_queued_frames) {
			current.dropped[stream]++;
			if (open_gap[stream] != NO_GAP) {
				// The gap goes on: it ends at this frame.
				Gap &gap = gaps[open_gap[stream]];
				gap.last_s = p_timestamp_s;
				gap.frames++;
			} else {
				open_gap[stream] = gaps.size();
				gaps.push_back({ p_item.stream, p_timestamp_s, p_timestamp_s, 1 });
				current.gaps = gaps.size();
			}
			return false;
		}
		open_gap[stream] = NO_GAP;
		queue.push_back(std::move(p_item));
		current.queued = queue.size();
	}
	wake.notify_one();
	return true;
}

void RecordingQueue::run() {
	for (;;) {
		Item item;
		{
			std::unique_lock lock(mutex);
			wake.wait(lock, [&] { return closing || !queue.empty(); });
			if (queue.empty()) {
				return; // closing, and everything is written
			}
			item = std::move(queue.front());
			queue.pop_front();
		}
		const RecordingStatus written = item.stream == RecordingStream::Rgbd ? writer.add_rgbd(item.rgbd) : writer.add_fisheye(item.fisheye);
		std::lock_guard lock(mutex);
		current.queued = queue.size();
		if (!written.ok) {
			if (current.error.empty()) {
				current.error = written.error;
			}
			queue.clear(); // a failing disk: stop taking frames (push_* now return false)
			current.queued = 0;
			continue;
		}
		current.written[int(item.stream)]++;
		current.megabytes_written = double(writer.get_image_bytes()) * 1e-6;
	}
}

std::string RecordingQueue::write_gaps() const {
	const std::string path = writer.get_folder() + "/gaps.txt";
	std::ofstream file(path, std::ios::out | std::ios::trunc);
	file << "# RoomProbe recording: frames the recorder could not keep (its queue was full)\n"
		 << "# stream first_timestamp_s last_timestamp_s frames\n";
	for (const Gap &gap : gaps) {
		file << recording_stream_name(gap.stream) << " " << recording_io::format_number(gap.first_s) << " "
			 << recording_io::format_number(gap.last_s) << " " << gap.frames << "\n";
	}
	file.flush();
	return file ? "" : path + ": cannot be written";
}

RecordingStatus RecordingQueue::close() {
	{
		std::lock_guard lock(mutex);
		if (!current.recording) {
			RecordingStatus nothing;
			nothing.ok = true;
			return nothing;
		}
		closing = true;
	}
	wake.notify_all();
	if (writer_thread.joinable()) {
		writer_thread.join();
	}
	std::string error;
	{
		std::lock_guard lock(mutex);
		error = current.error;
		if (!gaps.empty()) {
			const std::string gap_error = write_gaps();
			error = error.empty() ? gap_error : error;
		}
	}
	const RecordingStatus closed = writer.close();
	std::lock_guard lock(mutex);
	if (error.empty() && !closed.ok) {
		error = closed.error;
	}
	current.seconds = steady_s() - started_s;
	current.megabytes_per_s = current.seconds > 0.0 ? current.megabytes_written / current.seconds : 0.0;
	current.recording = false;
	current.queued = 0;
	current.error = error;
	RecordingStatus status;
	status.ok = error.empty();
	status.error = error;
	return status;
}

RecordingQueueStatus RecordingQueue::status() const {
	std::lock_guard lock(mutex);
	RecordingQueueStatus copy = current;
	if (copy.recording) {
		copy.seconds = steady_s() - started_s;
		copy.megabytes_per_s = copy.seconds > 0.0 ? copy.megabytes_written / copy.seconds : 0.0;
	}
	return copy;
}

} // namespace roomprobe
