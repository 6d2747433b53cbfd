#pragma once
// A latest-value mailbox between two threads (docs/ARCHITECTURE.md §3): the writer overwrites,
// the reader takes the newest, and a value overwritten before anyone took it is counted as
// dropped. A slow stage therefore drops frames instead of falling ever further behind.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>

namespace roomprobe {

template <typename T>
class Mailbox {
public:
	// Puts p_value in, replacing (and counting as dropped) one nobody took.
	void put(T p_value) {
		{
			const std::lock_guard<std::mutex> lock(mutex);
			if (value.has_value()) {
				dropped++;
			}
			value = std::move(p_value);
			puts++;
		}
		ready.notify_all();
	}

	// The newest value, or nothing when there is none by p_timeout or after close().
	std::optional<T> take(std::chrono::milliseconds p_timeout) {
		std::unique_lock<std::mutex> lock(mutex);
		ready.wait_for(lock, p_timeout, [this] { return value.has_value() || closed; });
		std::optional<T> out = std::move(value);
		value.reset();
		return out;
	}

	// The newest value if there is one, without waiting.
	std::optional<T> try_take() {
		const std::lock_guard<std::mutex> lock(mutex);
		std::optional<T> out = std::move(value);
		value.reset();
		return out;
	}

	// Wakes every waiting reader; take() returns at once until reopen().
	void close() {
		{
			const std::lock_guard<std::mutex> lock(mutex);
			closed = true;
		}
		ready.notify_all();
	}
	// Opens it again after close(), keeping its value and counts.
	void open() {
		const std::lock_guard<std::mutex> lock(mutex);
		closed = false;
	}
	// Opens it again, empty, with its counts at zero.
	void reopen() {
		const std::lock_guard<std::mutex> lock(mutex);
		closed = false;
		value.reset();
		dropped = puts = 0;
	}

	// Whether a value waits to be taken.
	bool pending() const {
		const std::lock_guard<std::mutex> lock(mutex);
		return value.has_value();
	}
	uint64_t dropped_count() const {
		const std::lock_guard<std::mutex> lock(mutex);
		return dropped;
	}
	uint64_t put_count() const {
		const std::lock_guard<std::mutex> lock(mutex);
		return puts;
	}

private:
	mutable std::mutex mutex;
	std::condition_variable ready;
	std::optional<T> value;
	bool closed = false;
	uint64_t dropped = 0;
	uint64_t puts = 0;
};

} // namespace roomprobe
