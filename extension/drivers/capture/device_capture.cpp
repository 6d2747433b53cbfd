#include "capture/device_capture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace roomprobe::drivers {

const char *device_state_name(DeviceState p_state) {
	switch (p_state) {
		case DeviceState::Stopped:
			return "stopped";
		case DeviceState::Connecting:
			return "connecting";
		case DeviceState::Streaming:
			return "streaming";
		case DeviceState::Stalled:
			return "stalled";
		case DeviceState::Disconnected:
			return "disconnected";
	}
	return "unknown";
}

namespace {

std::string seconds_text(double p_seconds) {
	char text[32];
	std::snprintf(text, sizeof(text), "%.1f s", p_seconds);
	return text;
}

} // namespace

DeviceCapture::DeviceCapture(std::unique_ptr<CaptureSource> p_source, const DeviceCaptureOptions &p_options, FrameSink p_on_frame, StateSink p_on_state) :
		source(std::move(p_source)), options(p_options), on_frame(std::move(p_on_frame)), on_state(std::move(p_on_state)) {
	source_name = source ? source->name() : "no device";
	if (!options.clock) {
		options.clock = monotonic_clock_ns;
	}
}

DeviceCapture::~DeviceCapture() {
	stop();
}

std::string DeviceCapture::start() {
	const auto bad = [&](const char *p_option, double p_value, const char *p_rule) {
		return source_name + ": capture option " + p_option + " = " + std::to_string(p_value) + " " + p_rule;
	};
	if (!source) {
		return "capture: no device to capture from";
	}
	if (!std::isfinite(options.latency_s) || options.latency_s < 0.0 || options.latency_s > 1.0) {
		return bad("latency_s", options.latency_s, "must be within 0 to 1 s");
	}
	if (!std::isfinite(options.stall_after_s) || options.stall_after_s <= 0.0) {
		return bad("stall_after_s", options.stall_after_s, "must be a positive number of seconds");
	}
	if (!std::isfinite(options.reopen_after_s) || options.reopen_after_s < options.stall_after_s) {
		return bad("reopen_after_s", options.reopen_after_s, "must be at least stall_after_s");
	}
	if (!std::isfinite(options.retry_first_s) || options.retry_first_s <= 0.0 || !std::isfinite(options.retry_max_s) || options.retry_max_s < options.retry_first_s) {
		return bad("retry_first_s", options.retry_first_s, "must be positive and at most retry_max_s");
	}
	if (options.grab_timeout_ms < 1 || options.grab_timeout_ms > 10000) {
		return bad("grab_timeout_ms", options.grab_timeout_ms, "must be within 1 to 10000 ms");
	}
	std::lock_guard lock(mutex);
	if (thread.joinable()) {
		return "";
	}
	stopping = false;
	interrupted = false;
	current = DeviceStatus();
	thread = std::thread([this] { run(); });
	return "";
}

void DeviceCapture::stop() {
	{
		std::lock_guard lock(mutex);
		stopping = true;
	}
	wake.notify_all();
	if (thread.joinable()) {
		thread.join();
	}
	std::lock_guard lock(mutex);
	if (current.state != DeviceState::Stopped) {
		current.state = DeviceState::Stopped;
		current.reason = "stopped";
		current.changes++;
	}
}

bool DeviceCapture::is_running() const {
	std::lock_guard lock(mutex);
	return thread.joinable() && !stopping;
}

DeviceStatus DeviceCapture::status() const {
	std::lock_guard lock(mutex);
	return current;
}

double DeviceCapture::now_s() const {
	return double(options.clock()) * 1e-9;
}

void DeviceCapture::set_state(DeviceState p_state, const std::string &p_reason) {
	DeviceStatus copy;
	{
		std::lock_guard lock(mutex);
		if (current.state == p_state && current.reason == p_reason) {
			return;
		}
		if ((p_state == DeviceState::Disconnected || p_state == DeviceState::Stalled) && current.frames > 0) {
			interrupted = true;
		}
		if (p_state == DeviceState::Streaming && interrupted) {
			current.reconnections++;
			interrupted = false;
		}
		current.state = p_state;
		current.reason = p_reason;
		current.changes++;
		copy = current;
	}
	if (on_state) {
		on_state(copy);
	}
}

bool DeviceCapture::wait(double p_seconds) {
	std::unique_lock lock(mutex);
	wake.wait_for(lock, std::chrono::duration<double>(p_seconds), [&] { return stopping; });
	return !stopping;
}

void DeviceCapture::run() {
	const auto stop_requested = [&] {
		std::lock_guard lock(mutex);
		return stopping;
	};
	double backoff_s = options.retry_first_s;
	while (!stop_requested()) {
		set_state(DeviceState::Connecting, source_name + ": opening");
		const DriverStatus opened = source->open();
		if (!opened.ok()) {
			set_state(DeviceState::Disconnected, opened.error + " (trying again in " + seconds_text(backoff_s) + ")");
			if (!wait(backoff_s)) {
				break;
			}
			backoff_s = std::min(backoff_s * 2.0, options.retry_max_s);
			continue;
		}
		set_state(DeviceState::Connecting, source_name + ": open, waiting for the first frame");
		double last_frame_s = now_s(); // the open counts as the start of the wait
		bool streamed = false;
		std::string lost;
		while (!stop_requested()) {
			GrabOutcome outcome = source->grab(options.grab_timeout_ms);
			if (outcome.kind == GrabOutcome::Frame) {
				// Stamped here, on the one clock, at the driver's hand-over (before the source's
				// conversion); strictly increasing even if the clock handed in steps back (a wall
				// clock would), so frames never reorder.
				CapturedFrame &frame = outcome.frame;
				const uint64_t processing_ns = uint64_t(std::clamp(frame.processing_s, 0.0, 1.0) * 1e9);
				uint64_t stamp_ns = options.clock();
				stamp_ns = stamp_ns > processing_ns ? stamp_ns - processing_ns : 0;
				stamp_ns = std::max(stamp_ns, last_stamp_ns + 1000);
				last_stamp_ns = stamp_ns;
				last_frame_s = double(stamp_ns) * 1e-9;
				frame.host_time_s = last_frame_s - options.latency_s;
				if (frame.is_rgbd) {
					frame.rgbd.timestamp_s = frame.host_time_s;
					frame.rgbd.depth_timestamp_s = frame.host_time_s;
				} else {
					frame.fisheye.timestamp_s = frame.host_time_s;
				}
				{
					std::lock_guard lock(mutex);
					current.frames++;
					current.last_frame_host_time_s = frame.host_time_s;
				}
				if (!streamed) {
					streamed = true;
					backoff_s = options.retry_first_s;
				}
				set_state(DeviceState::Streaming, "");
				if (on_frame) {
					on_frame(std::move(frame));
				}
				continue;
			}
			if (outcome.kind == GrabOutcome::Lost) {
				lost = outcome.error;
				break;
			}
			const double quiet_s = std::max(0.0, now_s() - last_frame_s);
			if (quiet_s >= options.reopen_after_s) {
				lost = source_name + ": no frame for " + seconds_text(quiet_s) + "; reopening it";
				break;
			}
			if (quiet_s >= options.stall_after_s) {
				set_state(DeviceState::Stalled, source_name + ": no frame for over " + seconds_text(options.stall_after_s) +
								(outcome.error.empty() ? std::string() : " (" + outcome.error + ")"));
			}
		}
		if (lost.empty()) {
			break; // stop() asked: closed below
		}
		source->close();
		set_state(DeviceState::Disconnected, lost + " (trying again in " + seconds_text(backoff_s) + ")");
		if (!wait(backoff_s)) {
			break;
		}
		backoff_s = std::min(backoff_s * 2.0, options.retry_max_s);
	}
	source->close();
}

} // namespace roomprobe::drivers
