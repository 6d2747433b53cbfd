#pragma once
// Accuracy of an estimated camera trajectory against the ground truth, as the TUM RGB-D benchmark
// defines it (Sturm, Engelhard, Endres, Burgard, Cremers, "A Benchmark for the Evaluation of RGB-D
// SLAM Systems", IROS 2012; its evaluate_ate.py and evaluate_rpe.py), with one difference: no
// alignment. RoomProbe's tracker starts at the ground truth's pose of its first frame, so both
// trajectories are in the same world frame and an error is an error of the tracker, not of a fit.
//
// The ground truth is taken at each estimated pose's timestamp (Trajectory::pose_at: interpolated
// between its samples, none outside them); estimated poses without one are left out.
//
// ATE: the translational distance between each estimated pose P_i and the ground truth Q_i.
// RPE: for pairs (i, j) of estimated poses a fixed delta apart, the error of the relative motion,
//   E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j);
// its translation's length (metres per delta) and its rotation's angle (degrees per delta). RPE is
// the drift per delta, blind to where the trajectory sits in the world.

#include <rig/trajectory.h>

#include <cstddef>

namespace roomprobe {

struct AbsoluteTrajectoryError {
	size_t count = 0; // estimated poses with a ground-truth pose at their timestamp
	double rmse_m = 0.0, mean_m = 0.0, max_m = 0.0; // translation; 0 when count is 0
	double max_at_s = 0.0; // timestamp of the largest error
	double rotation_rmse_deg = 0.0; // angle between the estimated and true rotations
	double path_m = 0.0; // length of the ground truth's path over the compared poses
};

AbsoluteTrajectoryError absolute_trajectory_error(const Trajectory &p_estimate, const Trajectory &p_truth);

// How RPE's pairs are a delta apart: in estimated samples (frames), or in seconds (the sample
// whose timestamp is closest to t_i + delta, as evaluate_rpe.py pairs them, when it is within
// half the mean frame interval of it: no pair across a gap or past the end).
enum class RpeDelta {
	Frames,
	Seconds,
};

struct RelativePoseError {
	size_t pairs = 0; // pairs with ground truth at both ends
	double translation_rmse_m = 0.0, translation_mean_m = 0.0, translation_max_m = 0.0; // metres per delta
	double rotation_rmse_deg = 0.0, rotation_mean_deg = 0.0, rotation_max_deg = 0.0; // degrees per delta
};

// p_delta > 0: a whole number of frames (1: consecutive frames), or seconds.
RelativePoseError relative_pose_error(const Trajectory &p_estimate, const Trajectory &p_truth, double p_delta, RpeDelta p_unit);

} // namespace roomprobe
