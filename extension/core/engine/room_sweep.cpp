#include "room_sweep.h"

#include "engine_config.h"

#include <source/recording_player.h>

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

// One probe 1 m up at the floorplan's centroid, or, when that lies outside (an L), where the
// camera first was.
glm::dvec3 default_probe(const RoomInfo &p_room) {
	const std::vector<Vec2> &points = p_room.floorplan.points;
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
	if (distance_outside_room_m(p_room.floorplan, Vec3{ centre.x, centre.y, centre.z }) > 0.0) {
		const glm::dvec3 camera = p_room.initial_rgb_pose.translation;
		centre = glm::dvec3(camera.x, 1.0, camera.z);
	}
	return centre;
}

// The engine's configuration for the sweep: dense SLAM alone, finding the room.
void sweep_config(const RecordingReader &p_reader, const RoomSweepOptions &p_options, LiveRoomConfig *r_config) {
	// The room is what is sought: nothing of room.yaml, and no photometry (the fisheye views are
	// searched for edges as recorded, so the recording's photometry is not read).
	config_from_recording(p_reader, RigPhotometry(), false, r_config);
	r_config->keep_points.clear();
	r_config->initial_rgb_pose = Pose(); // the dense model's frame: the first RGB-D frame's camera
	r_config->has_room = false;
	r_config->dense = true;
	r_config->find_room = true;
	r_config->room_estimation = p_options.estimation;
	if (p_options.voxel_size_m > 0.0f) {
		r_config->slam.tsdf.voxel_size_m = p_options.voxel_size_m;
	}
	r_config->slam.tsdf.max_depth_m = p_options.max_depth_m;
	if (p_options.true_poses) {
		r_config->dense_poses = PoseSource::GroundTruth;
		r_config->coarse_poses = PoseSource::GroundTruth;
	}
}

} // namespace

RoomSweepResult sweep_room(const RoomSweepOptions &p_options) {
	RoomSweepResult failed;
	RecordingPlayer player;
	PlayerOptions play;
	play.max_seconds = p_options.max_seconds;
	const std::string opened = open_player(p_options.recording, play, &player);
	if (!opened.empty()) {
		failed.error = opened;
		return failed;
	}
	const RecordingReader &reader = player.reader();
	const bool has_truth = reader.has_ground_truth_trajectory(RecordingStream::Rgbd);
	if (p_options.true_poses && !has_truth) {
		failed.error = p_options.recording + ": no ground-truth RGB-D trajectory, so no true poses to fuse at";
		return failed;
	}
	LiveRoomConfig config;
	sweep_config(reader, p_options, &config);
	LiveRoom engine;
	const std::string configured = engine.configure(config);
	if (!configured.empty()) {
		failed.error = p_options.recording + ": " + configured;
		return failed;
	}
	std::vector<size_t> fisheye_indices;
	size_t rgbd_frames = 0;
	for (size_t e = 0; e < player.events().size(); e++) {
		if (p_options.cancel != nullptr && p_options.cancel->load()) {
			failed.error = p_options.recording + ": cancelled";
			return failed;
		}
		const PlaybackEvent &event = player.events()[e];
		if (event.stream == RecordingStream::Fisheye) {
			fisheye_indices.push_back(event.index); // read below: only some are searched
			continue;
		}
		SourceFrame frame = player.read(e);
		if (!frame.ok) {
			say(p_options, "skipping RGB-D frame: " + frame.error);
			continue;
		}
		engine.push_rgbd(std::move(frame.rgbd));
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
		result.room.probes.push_back(default_probe(result.room));
	}
	return result;
}

} // namespace roomprobe
