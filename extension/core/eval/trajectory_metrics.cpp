#include "trajectory_metrics.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace roomprobe {

namespace {

// The angle of a rotation, degrees in [0, 180].
double angle_deg(const glm::dquat &p_rotation) {
	const double w = std::min(1.0, std::abs(p_rotation.w) / glm::length(p_rotation));
	return 2.0 * std::acos(w) * 180.0 / std::numbers::pi;
}

} // namespace

AbsoluteTrajectoryError absolute_trajectory_error(const Trajectory &p_estimate, const Trajectory &p_truth) {
	AbsoluteTrajectoryError result;
	double sum_squared = 0.0, sum = 0.0, sum_squared_deg = 0.0;
	bool has_last = false;
	glm::dvec3 last_truth(0.0);
	for (const TimedPose &sample : p_estimate.get_samples()) {
		Pose truth;
		std::string error;
		if (p_truth.is_empty() || !p_truth.pose_at(sample.t_s, &truth, &error)) {
			continue;
		}
		const double e = glm::length(sample.world_from_camera.translation - truth.translation);
		const double r = angle_deg(glm::inverse(truth.rotation) * sample.world_from_camera.rotation);
		result.count++;
		sum_squared += e * e;
		sum += e;
		sum_squared_deg += r * r;
		if (e > result.max_m || result.count == 1) {
			result.max_m = e;
			result.max_at_s = sample.t_s;
		}
		if (has_last) {
			result.path_m += glm::length(truth.translation - last_truth);
		}
		last_truth = truth.translation;
		has_last = true;
	}
	if (result.count > 0) {
		const double n = double(result.count);
		result.rmse_m = std::sqrt(sum_squared / n);
		result.mean_m = sum / n;
		result.rotation_rmse_deg = std::sqrt(sum_squared_deg / n);
	}
	return result;
}

RelativePoseError relative_pose_error(const Trajectory &p_estimate, const Trajectory &p_truth, double p_delta, RpeDelta p_unit) {
	RelativePoseError result;
	const std::vector<TimedPose> &samples = p_estimate.get_samples();
	if (!(p_delta > 0.0) || p_truth.is_empty() || samples.size() < 2) {
		return result;
	}
	// The ground truth at every estimated timestamp (false where it has none).
	std::vector<Pose> truth(samples.size());
	std::vector<bool> has_truth(samples.size(), false);
	for (size_t i = 0; i < samples.size(); i++) {
		std::string error;
		has_truth[i] = p_truth.pose_at(samples[i].t_s, &truth[i], &error);
	}
	const size_t frames = p_unit == RpeDelta::Frames ? size_t(std::llround(p_delta)) : 0;
	if (p_unit == RpeDelta::Frames && frames == 0) {
		return result;
	}
	// Seconds: a pair's far end may be off t_i + delta by half a frame, not across a gap.
	const double tolerance_s = 0.5 * (samples.back().t_s - samples.front().t_s) / double(samples.size() - 1);
	double sum_squared_m = 0.0, sum_m = 0.0, sum_squared_deg = 0.0, sum_deg = 0.0;
	for (size_t i = 0; i < samples.size(); i++) {
		size_t j = i + frames;
		if (p_unit == RpeDelta::Seconds) {
			// The sample closest to t_i + delta.
			const double target = samples[i].t_s + p_delta;
			const auto after = std::lower_bound(samples.begin(), samples.end(), target,
					[](const TimedPose &p_sample, double p_t) { return p_sample.t_s < p_t; });
			j = size_t(after - samples.begin());
			if (j == samples.size() || (j > 0 && target - samples[j - 1].t_s < samples[j].t_s - target)) {
				j--;
			}
			if (j <= i || std::abs(samples[j].t_s - target) > tolerance_s) {
				continue;
			}
		}
		if (j >= samples.size() || !has_truth[i] || !has_truth[j]) {
			continue;
		}
		const Pose true_motion = compose(inverse(truth[i]), truth[j]);
		const Pose estimated_motion = compose(inverse(samples[i].world_from_camera), samples[j].world_from_camera);
		const Pose error = compose(inverse(true_motion), estimated_motion);
		const double e = glm::length(error.translation);
		const double r = angle_deg(error.rotation);
		result.pairs++;
		sum_squared_m += e * e;
		sum_m += e;
		sum_squared_deg += r * r;
		sum_deg += r;
		result.translation_max_m = std::max(result.translation_max_m, e);
		result.rotation_max_deg = std::max(result.rotation_max_deg, r);
	}
	if (result.pairs > 0) {
		const double n = double(result.pairs);
		result.translation_rmse_m = std::sqrt(sum_squared_m / n);
		result.translation_mean_m = sum_m / n;
		result.rotation_rmse_deg = std::sqrt(sum_squared_deg / n);
		result.rotation_mean_deg = sum_deg / n;
	}
	return result;
}

} // namespace roomprobe
