#include "room_sweep.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cstdio>

namespace roomprobe {

namespace {

void say(const RoomSweepOptions &p_options, const std::string &p_line) {
	if (p_options.progress) {
		p_options.progress(p_line);
	}
}

} // namespace

RoomSweepResult estimate_room_in_engine(const LiveRoom &p_engine, const Rig &p_rig, const std::vector<FisheyeFrame> &p_fisheye,
		const RoomEstimationOptions &p_options) {
	RoomSweepResult result;
	result.ok = true;
	const std::shared_ptr<const DenseMeshSnapshot> mesh = p_engine.dense_mesh();
	if (mesh != nullptr && mesh->mesh != nullptr) {
		result.samples = surface_samples(*mesh->mesh);
	}
	const Trajectory trajectory = p_engine.trajectory();
	std::vector<glm::dvec3> cameras;
	for (const TimedPose &pose : trajectory.get_samples()) {
		cameras.push_back(pose.world_from_camera.translation);
	}
	// Up, roughly: the upward fisheye's axis, else the RGB camera's -y (held upright).
	glm::dvec3 up_hint(0.0, 1.0, 0.0);
	if (!trajectory.get_samples().empty()) {
		const Pose &first = trajectory.get_samples().front().world_from_camera;
		up_hint = p_rig.has_fisheye() ? first.rotation * (p_rig.rgb_from_fisheye.rotation * glm::dvec3(0.0, 0.0, 1.0)) : first.rotation * glm::dvec3(0.0, -1.0, 0.0);
	}
	result.estimate = estimate_room(result.samples, up_hint, cameras, p_options);
	RoomEstimate &estimate = result.estimate;
	result.world_from_model = estimate.world_from_model;
	const bool has_floorplan = estimate.state == RoomEstimateState::Complete || estimate.state == RoomEstimateState::Partial;
	if (has_floorplan && p_rig.has_fisheye()) {
		std::vector<FisheyeView> views;
		double highest_camera_m = 0.0;
		for (const glm::dvec3 &camera : cameras) {
			highest_camera_m = std::max(highest_camera_m, transform_point(estimate.world_from_model, camera).y);
		}
		for (const FisheyeFrame &frame : p_fisheye) {
			Pose model_from_fisheye;
			std::string error;
			if (p_engine.fisheye_pose(frame.timestamp_s, &model_from_fisheye, &error)) {
				views.push_back({ frame.image, compose(estimate.world_from_model, model_from_fisheye) });
			}
		}
		if (estimate.floorplan.ceiling_height_m <= 0.0) {
			const double lowest_m = std::max(p_options.min_ceiling_height_m, highest_camera_m + 0.3);
			if (lowest_m < p_options.max_ceiling_height_m) {
				result.fisheye_ceiling = ceiling_from_fisheye(views, p_rig.fisheye, estimate.floorplan, lowest_m, p_options.max_ceiling_height_m,
						estimate.edge_confidence);
			} else {
				result.fisheye_ceiling.message = "the camera went within 0.3 m of the highest ceiling searched (" +
						std::to_string(p_options.max_ceiling_height_m) + " m): no ceiling above it to search";
			}
			if (result.fisheye_ceiling.ok) {
				estimate.floorplan.ceiling_height_m = result.fisheye_ceiling.height_m;
				estimate.ceiling_source = "fisheye";
			}
		}
		if (estimate.floorplan.ceiling_height_m > 0.0) { // the edges never seen as walls, from the fisheye
			const std::vector<double> before = estimate.edge_confidence;
			result.fisheye_walls = complete_walls_from_fisheye(views, p_rig.fisheye, &estimate.floorplan, &estimate.edge_confidence);
			// A moved edge's neighbours grew: their seen share is measured again.
			std::vector<double> measured = floorplan_edge_confidence(estimate.floorplan.points, estimate.walls);
			for (size_t i = 0; i < measured.size(); i++) {
				if (before[i] < 0.3 && estimate.edge_confidence[i] >= 0.3) {
					measured[i] = std::max(measured[i], estimate.edge_confidence[i]);
				}
			}
			estimate.edge_confidence = measured;
			rebase_room_origin(&estimate);
			result.world_from_model = estimate.world_from_model;
		}
	}
	if (has_floorplan) { // the state and its sentence, after the fisheye's part
		std::string unseen;
		for (size_t i = 0; i < estimate.edge_confidence.size(); i++) {
			unseen += estimate.edge_confidence[i] < 0.3 ? " " + std::to_string(i) : "";
		}
		const bool ceiling = estimate.floorplan.ceiling_height_m > 0.0;
		estimate.state = unseen.empty() && ceiling ? RoomEstimateState::Complete : RoomEstimateState::Partial;
		estimate.message = std::to_string(estimate.floorplan.points.size()) + " corners, " + std::to_string(estimate.walls.size()) + " walls in the dense model" +
				(estimate.manhattan ? " (at right angles)" : "") + (unseen.empty() ? "" : "; never seen as walls: edge" + unseen + " (the room ends there where the sweep's view did)") +
				(ceiling ? "" : "; no ceiling: not in the dense model, and " + (result.fisheye_ceiling.message.empty() ? std::string("no fisheye") : result.fisheye_ceiling.message));
	}
	if (has_floorplan && estimate.floorplan.ceiling_height_m > 0.0) {
		result.room.floorplan = estimate.floorplan;
		const Pose first = trajectory.get_samples().empty() ? Pose() : trajectory.get_samples().front().world_from_camera;
		result.room.initial_rgb_pose = compose(estimate.world_from_model, first);
	}
	return result;
}

RoomSweepResult sweep_room(const RoomSweepOptions &p_options) {
	RoomSweepResult failed;
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_options.recording);
	if (!opened.ok) {
		failed.error = opened.error;
		return failed;
	}
	const Rig &rig = reader.get_rig();
	const bool has_truth = reader.has_ground_truth_trajectory(RecordingStream::Rgbd);
	if (p_options.true_poses && !has_truth) {
		failed.error = p_options.recording + ": no ground-truth RGB-D trajectory, so no true poses to fuse at";
		return failed;
	}
	LiveRoomConfig config;
	config.rig = rig;
	config.has_room = false;
	config.dense = true;
	config.initial_rgb_pose = Pose(); // the dense model's frame: the first RGB-D frame's camera
	if (p_options.voxel_size_m > 0.0f) {
		config.slam.tsdf.voxel_size_m = p_options.voxel_size_m;
	}
	config.slam.tsdf.max_depth_m = p_options.max_depth_m;
	if (has_truth) {
		config.ground_truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	}
	if (p_options.true_poses) {
		config.dense_poses = PoseSource::GroundTruth;
		config.coarse_poses = PoseSource::GroundTruth;
	}
	LiveRoom engine;
	const std::string configured = engine.configure(config);
	if (!configured.empty()) {
		failed.error = p_options.recording + ": " + configured;
		return failed;
	}
	const std::vector<PlaybackEvent> &events = reader.get_events();
	const double start_s = events.empty() ? 0.0 : events.front().time_s;
	std::vector<size_t> fisheye_indices;
	size_t rgbd_frames = 0;
	for (const PlaybackEvent &event : events) {
		if (p_options.max_seconds > 0.0 && event.time_s - start_s > p_options.max_seconds) {
			break;
		}
		if (event.stream == RecordingStream::Fisheye) {
			fisheye_indices.push_back(event.index);
			continue;
		}
		RgbdFrameResult frame = reader.read_rgbd(event.index);
		if (!frame.ok) {
			say(p_options, "skipping RGB-D frame: " + frame.error);
			continue;
		}
		engine.push_rgbd(std::move(frame.frame));
		rgbd_frames++;
	}
	say(p_options, "fused " + std::to_string(rgbd_frames) + " RGB-D frames" + (p_options.true_poses ? " at their true poses" : ", tracked"));
	engine.update_dense_mesh();
	std::vector<FisheyeFrame> fisheye;
	const size_t wanted = std::min(p_options.fisheye_views, fisheye_indices.size());
	for (size_t k = 0; k < wanted; k++) {
		const size_t index = fisheye_indices[(k * fisheye_indices.size()) / wanted];
		FisheyeFrameResult frame = reader.read_fisheye(index);
		if (frame.ok) {
			fisheye.push_back(std::move(frame.frame));
		} else {
			say(p_options, "skipping fisheye frame: " + frame.error);
		}
	}
	RoomSweepResult result = estimate_room_in_engine(engine, rig, fisheye, p_options.estimation);
	result.rgbd_frames = rgbd_frames;
	if (reader.has_room()) {
		result.has_truth = true;
		result.truth = reader.get_room();
		// Tracking starts at the first frame's camera; true poses put the model in the true world.
		result.true_world_from_model = p_options.true_poses ? Pose() : result.truth.initial_rgb_pose;
		// The recording's probes, carried into the room found.
		const Pose found_from_true = compose(result.world_from_model, inverse(result.true_world_from_model));
		for (const glm::dvec3 &probe : result.truth.probes) {
			result.room.probes.push_back(transform_point(found_from_true, probe));
		}
	}
	if (result.room.probes.empty() && !result.room.floorplan.points.empty()) {
		// One probe 1 m up at the floorplan's centroid, or, when that lies outside (an L), where
		// the camera first was.
		const std::vector<Vec2> &points = result.room.floorplan.points;
		double area = 0.0;
		glm::dvec3 centre(0.0, 1.0, 0.0);
		for (size_t i = 0; i < points.size(); i++) {
			const Vec2 &a = points[i], &b = points[(i + 1) % points.size()];
			const double cross = a.x * b.y - b.x * a.y;
			area += cross;
			centre.x += (a.x + b.x) * cross;
			centre.z += (a.y + b.y) * cross;
		}
		centre.x /= 3.0 * area;
		centre.z /= 3.0 * area;
		if (distance_outside_room_m(result.room.floorplan, Vec3{ centre.x, centre.y, centre.z }) > 0.0) {
			const glm::dvec3 camera = result.room.initial_rgb_pose.translation;
			centre = glm::dvec3(camera.x, 1.0, camera.z);
		}
		result.room.probes.push_back(centre);
	}
	return result;
}

} // namespace roomprobe
