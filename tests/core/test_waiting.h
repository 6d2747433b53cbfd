#pragma once
// Small helpers for tests of threads (the capture tests): waiting for a condition, and text search.

#include <chrono>
#include <string>
#include <thread>

namespace roomprobe::test {

inline bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// Polls p_done every 5 ms for at most p_seconds; whether it came true.
template <class F>
bool wait_until(double p_seconds, F p_done) {
	const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(p_seconds);
	while (!p_done()) {
		if (std::chrono::steady_clock::now() > give_up) {
			return false;
		}
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
	return true;
}

} // namespace roomprobe::test
