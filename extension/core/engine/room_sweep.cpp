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
	config.find_room = true;
	config.room_estimation = p_options.estimation;
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
		if (p_options.cancel != nullptr && p_options.cancel->load()) {
			failed.error = p_options.recording + ": cancelled";
			return failed;
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
	RoomSweepResult result;
	result.ok = true;
	const std::shared_ptr<const FoundRoom> found = engine.find_room_now(&fisheye);
	result.estimate = found->result.estimate;
	result.fisheye_ceiling = found->result.fisheye_ceiling;
	result.fisheye_walls = found->result.fisheye_walls;
	result.world_from_model = result.estimate.world_from_model;
	result.samples = found->samples;
	if (found->result.has_room) {
		result.room.floorplan = result.estimate.floorplan;
		result.room.initial_rgb_pose = found->result.initial_rgb_pose;
	}
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
