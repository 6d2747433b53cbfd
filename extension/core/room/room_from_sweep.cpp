#include "room_from_sweep.h"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <exception>

namespace roomprobe {

glm::dvec3 sweep_up_hint(const Pose &p_model_from_first_rgb, bool p_has_fisheye, const Pose &p_rgb_from_fisheye) {
	return p_has_fisheye ? p_model_from_first_rgb.rotation * (p_rgb_from_fisheye.rotation * glm::dvec3(0.0, 0.0, 1.0))
						 : p_model_from_first_rgb.rotation * glm::dvec3(0.0, -1.0, 0.0);
}

Pose upright_first_rgb_pose(bool p_has_fisheye, const Pose &p_rgb_from_fisheye) {
	// The world's axes in the camera's frame: Y the hint, Z against the view levelled, X = Y x Z.
	const glm::dvec3 up = glm::normalize(sweep_up_hint(Pose(), p_has_fisheye, p_rgb_from_fisheye));
	glm::dvec3 view = glm::dvec3(0.0, 0.0, 1.0) - up.z * up;
	if (glm::length(view) < 1e-6) { // looking straight up or down: the camera's y sets the heading
		view = glm::dvec3(0.0, up.z > 0.0 ? 1.0 : -1.0, 0.0) - up.y * up;
	}
	const glm::dvec3 z = -glm::normalize(view);
	const glm::dvec3 x = glm::cross(up, z);
	const glm::dmat3 camera_from_world(x, up, z); // columns
	Pose pose;
	pose.rotation = glm::normalize(glm::quat_cast(glm::transpose(camera_from_world)));
	return pose;
}

namespace {

// The fisheye's part: the ceiling when the dense model has none, then the walls never seen.
void add_fisheye_evidence(const SweepObservations &p_observed, const RoomEstimationOptions &p_options, RoomFromSweep *io_found) {
	RoomEstimate &estimate = io_found->estimate;
	double highest_camera_m = 0.0;
	for (const glm::dvec3 &camera : p_observed.camera_positions) {
		highest_camera_m = std::max(highest_camera_m, transform_point(estimate.world_from_model, camera).y);
	}
	std::vector<FisheyeView> views;
	views.reserve(p_observed.fisheye_views.size());
	for (const FisheyeView &view : p_observed.fisheye_views) {
		views.push_back({ view.image, compose(estimate.world_from_model, view.world_from_fisheye) });
	}
	if (estimate.floorplan.ceiling_height_m <= 0.0) {
		const double lowest_m = std::max(p_options.min_ceiling_height_m, highest_camera_m + 0.3);
		if (lowest_m < p_options.max_ceiling_height_m) {
			io_found->fisheye_ceiling = ceiling_from_fisheye(views, p_observed.fisheye, estimate.floorplan, lowest_m, p_options.max_ceiling_height_m,
					estimate.edge_confidence);
		} else {
			io_found->fisheye_ceiling.message = "the camera went within 0.3 m of the highest ceiling searched (" +
					std::to_string(p_options.max_ceiling_height_m) + " m): no ceiling above it to search";
		}
		if (io_found->fisheye_ceiling.ok) {
			estimate.floorplan.ceiling_height_m = io_found->fisheye_ceiling.height_m;
			estimate.ceiling_source = "fisheye";
		}
	}
	if (estimate.floorplan.ceiling_height_m > 0.0) { // the edges never seen as walls, from the fisheye
		const std::vector<double> before = estimate.edge_confidence;
		io_found->fisheye_walls = complete_walls_from_fisheye(views, p_observed.fisheye, &estimate.floorplan, &estimate.edge_confidence);
		// A moved edge's neighbours grew: their seen share is measured again.
		std::vector<double> measured = floorplan_edge_confidence(estimate.floorplan.points, estimate.walls);
		for (size_t i = 0; i < measured.size(); i++) {
			if (before[i] < 0.3 && estimate.edge_confidence[i] >= 0.3) {
				measured[i] = std::max(measured[i], estimate.edge_confidence[i]);
			}
		}
		estimate.edge_confidence = measured;
		merge_floorplan_steps(&estimate.floorplan.points, &estimate.edge_confidence);
		rebase_room_origin(&estimate);
	}
}

} // namespace

RoomFromSweep find_room_from_sweep(const SweepObservations &p_observed, const RoomEstimationOptions &p_options) {
	RoomFromSweep found;
	RoomEstimate &estimate = found.estimate;
	try {
		estimate = estimate_room(p_observed.samples, p_observed.up_hint, p_observed.camera_positions, p_options);
		const bool has_floorplan = estimate.state == RoomEstimateState::Complete || estimate.state == RoomEstimateState::Partial;
		if (has_floorplan && p_observed.has_fisheye) {
			add_fisheye_evidence(p_observed, p_options, &found);
		}
		if (has_floorplan) { // the state and its sentence, after the fisheye's part
			// An edge too short to be a wall (a partition's end) between two walls seen is not missing.
			std::string unseen;
			const std::vector<double> &seen = estimate.edge_confidence;
			const std::vector<Vec2> &corners = estimate.floorplan.points;
			for (size_t i = 0; i < seen.size(); i++) {
				const size_t n = seen.size(), next = (i + 1) % n;
				const bool partition_end = std::hypot(corners[next].x - corners[i].x, corners[next].y - corners[i].y) < 0.3 &&
						seen[(i + n - 1) % n] >= 0.3 && seen[next] >= 0.3;
				unseen += seen[i] < 0.3 && !partition_end ? " " + std::to_string(i) : "";
			}
			const bool ceiling = estimate.floorplan.ceiling_height_m > 0.0;
			estimate.state = unseen.empty() && ceiling ? RoomEstimateState::Complete : RoomEstimateState::Partial;
			estimate.message = std::to_string(estimate.floorplan.points.size()) + " corners, " + std::to_string(estimate.walls.size()) +
					" walls in the dense model" + (estimate.manhattan ? " (at right angles)" : "") +
					(unseen.empty() ? "" : "; never seen as walls: edge" + unseen + " (the room ends there where the sweep's view did)") +
					(ceiling ? ""
							 : "; no ceiling: not in the dense model, and " +
									 (found.fisheye_ceiling.message.empty() ? std::string("no fisheye") : found.fisheye_ceiling.message));
			found.has_room = ceiling;
			found.initial_rgb_pose = compose(estimate.world_from_model, p_observed.has_first_camera ? p_observed.model_from_first_rgb : Pose());
		}
	} catch (const std::exception &e) {
		// CGAL's precondition failures and cv::Exception: a live caller gets a state, not a throw.
		found = RoomFromSweep();
		found.estimate.state = RoomEstimateState::NoSurface;
		found.estimate.message = std::string("the room's estimation failed: ") + e.what();
	}
	return found;
}

} // namespace roomprobe
