#pragma once
// The RGB-D camera's tracked poses, the seam between the engine's dense stage (which appends a
// pose per tracked frame) and its coarse stage (which poses each fisheye frame on it at the
// fisheye's instant, §4.3, and may wait for SLAM to get there). Its own lock.

#include <rig/fisheye_pose.h>
#include <rig/trajectory.h>

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>

namespace roomprobe {

class PoseHistory {
public:
	void clear();
	// A pose at p_time_s (a repeated timestamp is skipped); wakes a stage waiting for it.
	void append(double p_time_s, const Pose &p_world_from_camera);
	Trajectory copy() const;
	// The fisheye's pose at p_fisheye_timestamp_s on this history (fisheye_pose_at), extrapolated at
	// most p_extrapolation_s past its end. False, with r_error, when there is none.
	bool fisheye_pose(const Rig &p_rig, double p_fisheye_timestamp_s, double p_extrapolation_s, Pose *r_world_from_fisheye, std::string *r_error) const;
	// Waits until the history reaches p_time_s, at most p_max_wait_s, and only while
	// p_keep_waiting() holds (checked every 10 ms).
	void wait_until_reaches(double p_time_s, double p_max_wait_s, const std::function<bool()> &p_keep_waiting) const;
	void wake_all(); // a stopping engine: waiters look again

private:
	mutable std::mutex mutex;
	mutable std::condition_variable advanced;
	Trajectory poses;
};

} // namespace roomprobe
