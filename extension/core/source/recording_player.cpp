#include "recording_player.h"

#include <chrono>

namespace roomprobe {

RecordingPlayer::RecordingPlayer(std::shared_ptr<const RecordingReader> p_reader, const PlayerOptions &p_options) :
		reader_(std::move(p_reader)) {
	const std::vector<PlaybackEvent> &all = reader_->get_events();
	const double first_s = all.empty() ? 0.0 : all.front().time_s;
	for (const PlaybackEvent &event : all) {
		if (p_options.max_seconds > 0.0 && event.time_s - first_s > p_options.max_seconds) {
			break;
		}
		const bool rgbd = event.stream == RecordingStream::Rgbd;
		if (rgbd && p_options.max_rgbd_frames > 0 && rgbd_events_ >= p_options.max_rgbd_frames) {
			break;
		}
		if (rgbd ? !p_options.rgbd : !p_options.fisheye) {
			continue;
		}
		rgbd_events_ += rgbd ? 1 : 0;
		events_.push_back(event);
	}
}

SourceFrame RecordingPlayer::read(size_t p_event) const {
	SourceFrame out;
	out.event = events_[p_event];
	const auto start = std::chrono::steady_clock::now();
	if (out.event.stream == RecordingStream::Rgbd) {
		RgbdFrameResult result = reader_->read_rgbd(out.event.index);
		out.ok = result.ok;
		out.error = std::move(result.error);
		out.rgbd = std::move(result.frame);
	} else {
		FisheyeFrameResult result = reader_->read_fisheye(out.event.index);
		out.ok = result.ok;
		out.error = std::move(result.error);
		out.fisheye = std::move(result.frame);
	}
	out.read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	return out;
}

SourceFrame RecordingPlayer::next() {
	if (at_end()) {
		SourceFrame end;
		end.error = "end";
		return end;
	}
	return read(next_++);
}

std::vector<size_t> RecordingPlayer::take_until(double p_time_s) {
	std::vector<size_t> out;
	// The small margin takes an event stamped at the very instant, written in another rounding.
	while (next_ < events_.size() && events_[next_].time_s <= p_time_s + 1e-6) {
		out.push_back(next_++);
	}
	return out;
}

std::vector<size_t> RecordingPlayer::take_due(double p_elapsed_s, DropPolicy p_drop, size_t *r_dropped) {
	const std::vector<size_t> due = take_until(start_s() + p_elapsed_s);
	if (p_drop == DropPolicy::None) {
		return due;
	}
	std::vector<size_t> out;
	for (size_t k = 0; k < due.size(); k++) {
		bool newest = true;
		for (size_t later = k + 1; later < due.size() && newest; later++) {
			newest = events_[due[later]].stream != events_[due[k]].stream;
		}
		if (newest) {
			out.push_back(due[k]);
		} else if (r_dropped != nullptr) {
			(*r_dropped)++;
		}
	}
	return out;
}

std::string open_player(const std::string &p_folder, const PlayerOptions &p_options, RecordingPlayer *r_player) {
	auto reader = std::make_shared<RecordingReader>();
	const RecordingStatus status = reader->open(p_folder);
	if (!status.ok) {
		return status.error;
	}
	*r_player = RecordingPlayer(std::move(reader), p_options);
	return std::string();
}

} // namespace roomprobe
