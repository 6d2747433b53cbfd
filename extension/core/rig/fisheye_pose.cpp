#include "fisheye_pose.h"

#include <charconv>

namespace roomprobe {

namespace {

std::string format_double(double p_value) {
	char buffer[64];
	const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), p_value);
	return std::string(buffer, result.ptr);
}

} // namespace

bool fisheye_pose_at(const Trajectory &p_rgb_trajectory, const Rig &p_rig, double p_fisheye_timestamp_s,
		Pose *r_world_from_fisheye, std::string *r_error, double p_extrapolation_tolerance_s) {
	const double rgb_time_s = p_fisheye_timestamp_s + p_rig.fisheye_time_offset_s;
	Pose world_from_rgb;
	std::string error;
	if (!p_rgb_trajectory.pose_at(rgb_time_s, &world_from_rgb, &error, p_extrapolation_tolerance_s)) {
		*r_error = "fisheye frame at " + format_double(p_fisheye_timestamp_s) + " s (RGB-D clock " +
				format_double(rgb_time_s) + " s): " + error;
		return false;
	}
	*r_world_from_fisheye = compose(world_from_rgb, p_rig.rgb_from_fisheye);
	return true;
}

} // namespace roomprobe
