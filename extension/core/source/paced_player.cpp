#include "paced_player.h"

#include <algorithm>
#include <cmath>

namespace roomprobe {

void PacedPlayer::open(RecordingPlayer p_player) {
	stop();
	const std::lock_guard<std::mutex> lock(mutex);
	player = std::move(p_player);
	player.rewind();
	pass++;
	clock = 0.0;
	dropped_count = 0;
	end_reached = false;
}

void PacedPlayer::start(const PacedOptions &p_options, Sink p_sink) {
	stop();
	{
		const std::lock_guard<std::mutex> lock(mutex);
		options = p_options;
		// A speed of 0, below 0 or not a number would stop the wall clock (or run it backwards).
		options.speed = std::isfinite(options.speed) ? std::clamp(options.speed, 1e-3, 1e6) : 1.0;
		sink = std::move(p_sink);
		stopping = false;
		running = true;
		// The wall clock goes on from where the clock stands (0 after a rewind).
		wall_start = std::chrono::steady_clock::now() - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
																  std::chrono::duration<double>(clock / options.speed));
	}
	thread = std::thread([this] { run(); });
}

void PacedPlayer::stop() {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		if (running && options.clock == PaceClock::Wall) {
			clock = elapsed_locked(); // a later start() goes on from here
		}
		stopping = true;
	}
	wake.notify_all();
	if (thread.joinable() && thread.get_id() == std::this_thread::get_id()) {
		return; // from the sink or on_end: the thread ends after it; the owner's stop() or the destructor joins
	}
	if (thread.joinable()) {
		thread.join();
	}
	const std::lock_guard<std::mutex> lock(mutex);
	running = false;
}

void PacedPlayer::advance(double p_delta_s) {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		clock += p_delta_s;
	}
	wake.notify_all();
}

void PacedPlayer::rewind() {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		player.rewind();
		pass++;
		clock = 0.0;
		dropped_count = 0;
		end_reached = false;
		wall_start = std::chrono::steady_clock::now();
	}
	wake.notify_all();
}

bool PacedPlayer::reached_end() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return end_reached;
}

size_t PacedPlayer::dropped() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return dropped_count;
}

double PacedPlayer::clock_s() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return elapsed_locked();
}

bool PacedPlayer::at_end() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return player.at_end();
}

size_t PacedPlayer::position() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return player.position();
}

double PacedPlayer::elapsed_locked() const {
	if (options.clock == PaceClock::Manual || !running) {
		return clock;
	}
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count() * options.speed;
}

SourceFrame PacedPlayer::step(bool p_loop) {
	size_t event = 0;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		if (running) {
			SourceFrame busy;
			busy.error = "running";
			return busy;
		}
		if (player.at_end() && p_loop) {
			player.rewind();
			end_reached = false;
		}
		if (player.at_end()) {
			SourceFrame end;
			end.error = "end";
			return end;
		}
		clock = player.next_due_s();
		event = player.take_next();
	}
	return player.read(event);
}

void PacedPlayer::run() {
	std::unique_lock<std::mutex> lock(mutex);
	while (!stopping) {
		if (player.at_end()) {
			if (!end_reached) {
				end_reached = true; // the owner signals it, and rewinds when looping
				if (options.on_end) {
					lock.unlock();
					options.on_end();
					lock.lock();
				}
			}
			wake.wait(lock, [this] { return stopping || !player.at_end(); });
			continue;
		}
		const double elapsed = elapsed_locked();
		if (options.clock == PaceClock::Manual) {
			clock = elapsed;
		}
		const std::vector<size_t> due = player.take_due(elapsed, options.drop, &dropped_count);
		if (due.empty()) {
			if (options.clock == PaceClock::Manual) {
				wake.wait(lock);
			} else {
				// At most 0.1 s at a time: the clock is looked at again, whatever the speed.
				const double wait_s = std::clamp((player.next_due_s() - elapsed) / options.speed, 0.0, 0.1);
				wake.wait_for(lock, std::chrono::duration<double>(wait_s));
			}
			continue;
		}
		const double start_s = player.start_s();
		const std::vector<PlaybackEvent> &events = player.events(); // open() joins first: never replaced meanwhile
		const std::chrono::steady_clock::time_point batch_wall_start = wall_start;
		const uint64_t batch_pass = pass;
		lock.unlock();
		for (size_t e : due) {
			SourceFrame frame = player.read(e);
			if (options.clock == PaceClock::Wall) {
				const double due_s = (events[e].time_s - start_s) / options.speed;
				const double now_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_wall_start).count();
				frame.late_ms = 1000.0 * (now_s - due_s) - frame.read_ms;
			}
			{
				const std::lock_guard<std::mutex> check(mutex);
				if (pass != batch_pass) {
					break; // rewound meanwhile: the rest of the batch is the old pass's
				}
			}
			sink(std::move(frame));
		}
		lock.lock();
	}
}

} // namespace roomprobe
