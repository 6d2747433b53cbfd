// Trajectory accuracy (eval/trajectory_metrics.h): ATE and TUM's RPE on known perturbations of a
// ground-truth trajectory.

#include "eval/trajectory_metrics.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

constexpr double RATE_HZ = 30.0;

double radians(double p_degrees) {
	return p_degrees * std::numbers::pi / 180.0;
}

// A hand-held-like ground truth: turning about y and a tilted axis while moving, 30 Hz.
Trajectory make_truth(int p_count) {
	std::vector<TimedPose> samples;
	for (int i = 0; i < p_count; i++) {
		const double t = i / RATE_HZ;
		Pose pose;
		pose.rotation = glm::angleAxis(radians(20.0) * t, glm::dvec3(0.0, 1.0, 0.0)) * glm::angleAxis(radians(10.0) * t, glm::normalize(glm::dvec3(1.0, 0.0, 0.3)));
		pose.translation = glm::dvec3(0.3 * t, 1.5 + 0.05 * std::sin(t), -0.2 * t);
		samples.push_back({ 1000.0 + t, pose });
	}
	Trajectory trajectory;
	std::string error;
	REQUIRE_MESSAGE(trajectory.set_samples(std::move(samples), &error), error);
	return trajectory;
}

// Each step's motion followed by p_step_error: P_{i+1} = P_i (Q_i^-1 Q_{i+1}) D, from P_0 = Q_0.
Trajectory drift(const Trajectory &p_truth, const Pose &p_step_error) {
	const std::vector<TimedPose> &truth = p_truth.get_samples();
	std::vector<TimedPose> samples = { truth[0] };
	for (size_t i = 1; i < truth.size(); i++) {
		const Pose motion = compose(inverse(truth[i - 1].world_from_camera), truth[i].world_from_camera);
		samples.push_back({ truth[i].t_s, compose(compose(samples.back().world_from_camera, motion), p_step_error) });
	}
	Trajectory trajectory;
	std::string error;
	REQUIRE_MESSAGE(trajectory.set_samples(std::move(samples), &error), error);
	return trajectory;
}

} // namespace

TEST_CASE("trajectory metrics: the ground truth against itself has no error") {
	const Trajectory truth = make_truth(60);
	const AbsoluteTrajectoryError ate = absolute_trajectory_error(truth, truth);
	CHECK(ate.count == 60);
	CHECK(ate.rmse_m == doctest::Approx(0.0));
	CHECK(ate.rotation_rmse_deg < 1e-6);
	CHECK(ate.path_m > 0.3);
	const RelativePoseError rpe = relative_pose_error(truth, truth, 1.0, RpeDelta::Frames);
	CHECK(rpe.pairs == 59);
	CHECK(rpe.translation_rmse_m < 1e-12);
	CHECK(rpe.rotation_rmse_deg < 1e-5);
}

TEST_CASE("trajectory metrics: RPE per frame is a known step error, ATE grows with it") {
	const Trajectory truth = make_truth(90);
	// 1 mm along the camera's x and 0.5 degrees about its z every frame.
	Pose step;
	step.translation = glm::dvec3(0.001, 0.0, 0.0);
	step.rotation = glm::angleAxis(radians(0.5), glm::dvec3(0.0, 0.0, 1.0));
	const Trajectory estimate = drift(truth, step);

	const RelativePoseError per_frame = relative_pose_error(estimate, truth, 1.0, RpeDelta::Frames);
	CHECK(per_frame.pairs == 89);
	CHECK(per_frame.translation_rmse_m == doctest::Approx(0.001).epsilon(1e-9));
	CHECK(per_frame.translation_mean_m == doctest::Approx(0.001).epsilon(1e-9));
	CHECK(per_frame.translation_max_m == doctest::Approx(0.001).epsilon(1e-9));
	CHECK(per_frame.rotation_rmse_deg == doctest::Approx(0.5).epsilon(1e-6));
	CHECK(per_frame.rotation_max_deg == doctest::Approx(0.5).epsilon(1e-6));

	// Over 10 frames the errors compound (about ten steps' rotation: the true motion between the
	// steps turns their axes a little).
	const RelativePoseError per_ten = relative_pose_error(estimate, truth, 10.0, RpeDelta::Frames);
	CHECK(per_ten.pairs == 80);
	CHECK(per_ten.rotation_rmse_deg == doctest::Approx(5.0).epsilon(0.01));
	CHECK(per_ten.translation_rmse_m > 0.001);

	const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate, truth);
	CHECK(ate.count == 90);
	CHECK(ate.rmse_m > 0.01); // the drift adds up over 3 s
	CHECK(ate.max_at_s > 1002.0); // at the end
}

TEST_CASE("trajectory metrics: RPE per second pairs frames a second apart") {
	// A camera moving straight without turning, and a step error of 2 mm forward: over a second
	// (30 frames) the error is 30 steps, 60 mm.
	std::vector<TimedPose> samples;
	for (int i = 0; i < 90; i++) {
		Pose pose;
		pose.translation = glm::dvec3(0.01 * i, 1.5, 0.0);
		samples.push_back({ i / RATE_HZ, pose });
	}
	Trajectory truth;
	std::string error;
	REQUIRE(truth.set_samples(samples, &error));
	Pose step;
	step.translation = glm::dvec3(0.0, 0.0, 0.002);
	const Trajectory estimate = drift(truth, step);
	const RelativePoseError per_second = relative_pose_error(estimate, truth, 1.0, RpeDelta::Seconds);
	CHECK(per_second.pairs == 60); // frames 0..59 have a frame 1 s later
	CHECK(per_second.translation_rmse_m == doctest::Approx(0.060).epsilon(1e-9));
	CHECK(per_second.rotation_rmse_deg < 1e-6);
}

TEST_CASE("trajectory metrics: a rigid offset of the whole trajectory is ATE, not RPE") {
	const Trajectory truth = make_truth(60);
	// Shifted 3 mm and 4 mm in the world: ATE 5 mm everywhere, every relative motion exact.
	std::vector<TimedPose> shifted = truth.get_samples();
	for (TimedPose &sample : shifted) {
		sample.world_from_camera.translation += glm::dvec3(0.003, 0.004, 0.0);
	}
	Trajectory estimate;
	std::string error;
	REQUIRE(estimate.set_samples(shifted, &error));
	const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate, truth);
	CHECK(ate.rmse_m == doctest::Approx(0.005).epsilon(1e-9));
	CHECK(ate.max_m == doctest::Approx(0.005).epsilon(1e-9));
	CHECK(ate.rotation_rmse_deg < 1e-6);
	const RelativePoseError rpe = relative_pose_error(estimate, truth, 1.0, RpeDelta::Frames);
	CHECK(rpe.translation_rmse_m < 1e-12);

	// Estimated poses outside the ground truth's time range are left out, and so are their pairs.
	std::vector<TimedPose> longer = shifted;
	longer.push_back({ shifted.back().t_s + 1.0, shifted.back().world_from_camera });
	REQUIRE(estimate.set_samples(longer, &error));
	CHECK(absolute_trajectory_error(estimate, truth).count == 60);
	CHECK(relative_pose_error(estimate, truth, 1.0, RpeDelta::Frames).pairs == 59);
	CHECK(relative_pose_error(estimate, Trajectory(), 1.0, RpeDelta::Frames).pairs == 0);
}
