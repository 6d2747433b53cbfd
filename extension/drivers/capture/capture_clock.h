#pragma once
// The one clock of a live rig. Every capture thread stamps its frames on the host's monotonic
// clock (CLOCK_MONOTONIC, std::chrono::steady_clock) when the frame reaches the host, less the
// device's latency from the rig file. The RGB-D camera and the fisheye then share one time line,
// and it never jumps: setting the wall clock (NTP, the user, a suspended laptop's catch-up)
// changes neither the order nor the spacing of frames. The devices' own clocks are kept beside
// it (CapturedFrame::device_time_s) for recordings.

#include <chrono>
#include <cstdint>

namespace roomprobe::drivers {

// Reads a clock in nanoseconds. Captures take one so that tests can hand in a clock that
// misbehaves (one that steps back, as a wall clock does).
using ClockNs = uint64_t (*)();

// Nanoseconds on the host's monotonic clock.
inline uint64_t monotonic_clock_ns() {
	return uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
}

} // namespace roomprobe::drivers
