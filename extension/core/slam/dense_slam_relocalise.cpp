// DenseSlam's relocalisation after a loss (dense_slam.h): the search around the held pose, then
// the keyframes most like the frame (keyframes.h), verified by ICP and confirmed by the next frame.
// Split from dense_slam.cpp to keep each file short.
#include "dense_slam.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <numbers>
#include <string>
#include <vector>

namespace roomprobe {

IcpTracker DenseSlam::search_tracker() const {
	// Candidates: coarse levels only (the finest is the refinement's), and a jump limit that lets a
	// candidate's solve cover the distance between candidates.
	IcpOptions coarse = opts.icp;
	coarse.iterations[0] = 0;
	coarse.max_jump_m = opts.relocalise_max_m;
	coarse.max_jump_deg = opts.relocalise_max_deg;
	IcpTracker search = tracker; // on the tracker's device, if it has one
	search.set_options(coarse);
	return search;
}

TrackingResult DenseSlam::relocalise(const cv::Mat &p_depth_m, const cv::Mat &p_rgb) const {
	const IcpTracker search = search_tracker();
	std::vector<Pose> starts = { last_pose };
	const double step_rad = opts.relocalise_step_deg * std::numbers::pi / 180.0;
	for (int axis = 0; axis < 3; axis++) {
		for (const double sign : { -1.0, 1.0 }) {
			glm::dvec3 offset(0.0);
			offset[axis] = sign;
			Pose moved;
			moved.translation = offset * opts.relocalise_step_m;
			starts.push_back(compose(last_pose, moved));
			Pose turned;
			turned.rotation = glm::angleAxis(sign * step_rad, glm::normalize(offset * sign));
			starts.push_back(compose(last_pose, turned));
		}
	}
	TrackingResult best;
	best.reason = "relocalisation: no starting pose around the held one tracked";
	best.world_from_camera = last_pose;
	bool found = false;
	for (const Pose &start : starts) {
		const TrackingResult candidate = track_with(search, p_depth_m, p_rgb, start);
		if (candidate.state == TrackingState::Good && (!found || candidate.inlier_fraction > best.inlier_fraction)) {
			best = candidate;
			found = true;
		}
	}
	if (!found) {
		return best;
	}
	TrackingResult refined = track(p_depth_m, p_rgb, best.world_from_camera);
	const double away_m = translation_difference_m(refined.world_from_camera, last_pose);
	const double away_deg = rotation_difference_deg(refined.world_from_camera, last_pose);
	if (refined.state == TrackingState::Good && (away_m > opts.relocalise_max_m || away_deg > opts.relocalise_max_deg)) {
		refined.state = TrackingState::Lost;
		refined.reason = "relocalisation: the best pose is " + std::to_string(away_m) + " m and " + std::to_string(away_deg) +
				" deg from the held one, beyond the search's limits";
	}
	if (refined.state != TrackingState::Good) {
		refined.state = TrackingState::Lost;
		refined.world_from_camera = last_pose;
		if (refined.reason.empty()) {
			refined.reason = "relocalisation: the refined pose is not good";
		}
		return refined;
	}
	refined.relocalised = true;
	return refined;
}

TrackingResult DenseSlam::relocalise_at_keyframes(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, int *r_keyframe) const {
	TrackingResult none;
	none.world_from_camera = last_pose;
	none.reason = "relocalisation at the keyframes: no keyframe yet";
	if (keyframes.size() == 0) {
		return none;
	}
	const std::vector<size_t> candidates = keyframes.nearest(keyframes.thumbnail(p_depth_m, p_rgb), size_t(std::max(1, opts.relocalise_keyframes)));
	if (candidates.empty()) {
		none.reason = "relocalisation at the keyframes: the frame has too few readings to compare";
		return none;
	}
	const IcpTracker search = search_tracker(); // from the keyframe's pose, as the search around the held pose
	for (const size_t index : candidates) {
		const Keyframe &keyframe = keyframes.at(index);
		const TrackingResult near = track_against(search, reference_at(keyframe.world_from_camera), p_depth_m, p_rgb, keyframe.world_from_camera);
		if (near.state != TrackingState::Good) {
			continue;
		}
		TrackingResult found = track_against(tracker, reference_at(near.world_from_camera), p_depth_m, p_rgb, near.world_from_camera);
		if (found.state != TrackingState::Good) {
			continue;
		}
		*r_keyframe = keyframe.id;
		return found;
	}
	none.reason = "relocalisation at the keyframes: none of the " + std::to_string(candidates.size()) + " nearest of " + std::to_string(keyframes.size()) +
			" verified";
	return none;
}

TrackingResult DenseSlam::relocalise_far(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, double p_time_s) {
	if (candidate.pending) {
		// The frame after a keyframe's pose was found: tracked from that pose against the model
		// seen from it, it must be Good and within a hand's reach of it.
		candidate.pending = false;
		TrackingResult next = track_against(tracker, reference_at(candidate.pose), p_depth_m, p_rgb, candidate.pose);
		if (next.state == TrackingState::Good && faster_than_a_hand(next, p_time_s, candidate.pose, candidate.time_s).empty()) {
			next.relocalised = true;
			next.reason = "relocalised at keyframe " + std::to_string(candidate.keyframe);
			return next;
		}
	}
	int keyframe = -1;
	TrackingResult found = relocalise_at_keyframes(p_depth_m, p_rgb, &keyframe);
	if (found.state != TrackingState::Good) {
		return found;
	}
	candidate = { true, found.world_from_camera, p_time_s, keyframe };
	TrackingResult wait;
	wait.world_from_camera = last_pose;
	wait.reason = "relocalisation: found at keyframe " + std::to_string(keyframe) + ", to be confirmed by the next frame";
	return wait;
}

} // namespace roomprobe
