#include "pose_history.h"

#include <algorithm>
#include <chrono>

namespace roomprobe {

void PoseHistory::clear() {
	const std::lock_guard<std::mutex> lock(mutex);
	poses.clear();
}

void PoseHistory::append(double p_time_s, const Pose &p_world_from_camera) {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		std::string repeated;
		poses.append({ p_time_s, p_world_from_camera }, &repeated);
	}
	advanced.notify_all();
}

Trajectory PoseHistory::copy() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return poses;
}

bool PoseHistory::fisheye_pose(const Rig &p_rig, double p_fisheye_timestamp_s, double p_extrapolation_s, Pose *r_world_from_fisheye, std::string *r_error) const {
	const std::lock_guard<std::mutex> lock(mutex);
	if (poses.is_empty()) {
		*r_error = "no tracked RGB-D pose yet";
		return false;
	}
	return fisheye_pose_at(poses, p_rig, p_fisheye_timestamp_s, r_world_from_fisheye, r_error, p_extrapolation_s);
}

void PoseHistory::wait_until_reaches(double p_time_s, double p_max_wait_s, const std::function<bool()> &p_keep_waiting) const {
	// At most an hour: a longer (or infinite) wait would overflow the clock's nanoseconds.
	const double wait_s = std::min(p_max_wait_s, 3600.0);
	const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(wait_s));
	std::unique_lock<std::mutex> lock(mutex);
	while ((poses.is_empty() || poses.get_end_s() < p_time_s) && std::chrono::steady_clock::now() < deadline && p_keep_waiting()) {
		advanced.wait_for(lock, std::chrono::milliseconds(10));
	}
}

void PoseHistory::wake_all() {
	const std::lock_guard<std::mutex> lock(mutex);
	advanced.notify_all();
}

} // namespace roomprobe
