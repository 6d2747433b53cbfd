// CoarseRoomModel's room found from a sweep (coarse_room_model.h, issue #18): the engine's
// estimates taken as they come (floorplan_source Automatic), and a search over a recording on a
// thread of its own. Split from coarse_room_model.cpp to keep each file short.
#include "coarse_room_model.h"

#include "../convert/pose_convert.h"
#include "../convert/project_paths.h"

#include <cmath>
#include <thread>

using namespace godot;

namespace roomprobe {

// ---------------------------------------------------------------- the room from the sweep (issue #18)

void CoarseRoomModel::take_found_room() {
	if (floorplan_source != FLOORPLAN_AUTOMATIC || !engine || own_engine) {
		return;
	}
	const std::shared_ptr<const FoundRoom> newest = engine->found_room();
	if (!newest || newest == looked_at) {
		return;
	}
	looked_at = newest;
	if (newest->result.has_room && !worse_than_shown(*newest)) {
		apply_found_room(*newest);
		found = newest;
	}
	const RoomEstimate &estimate = newest->result.estimate;
	// After the room is applied: a handler sees the room of this estimate.
	emit_signal("room_estimated", String(room_estimate_state_name(estimate.state)), String(estimate.message.c_str()));
	update_configuration_warnings();
}

// Whether p_candidate would replace the room shown with a lesser one: a partial room after a
// complete one, or less wall seen (the walls' length times their seen share) by a tenth. A
// sweep's later estimate can lose a wall (blocks evicted, a view that confused the fisheye).
bool CoarseRoomModel::worse_than_shown(const FoundRoom &p_candidate) const {
	if (!found) {
		return false;
	}
	const auto seen_m = [](const RoomEstimate &p_estimate) {
		const std::vector<Vec2> &points = p_estimate.floorplan.points;
		double sum = 0.0;
		for (size_t i = 0; i < points.size() && i < p_estimate.edge_confidence.size(); i++) {
			const Vec2 &a = points[i], &b = points[(i + 1) % points.size()];
			sum += std::hypot(b.x - a.x, b.y - a.y) * p_estimate.edge_confidence[i];
		}
		return sum;
	};
	const RoomEstimate &now = found->result.estimate, &next = p_candidate.result.estimate;
	if (now.state == RoomEstimateState::Complete && next.state != RoomEstimateState::Complete) {
		return true;
	}
	return seen_m(next) < 0.9 * seen_m(now);
}

// Shows the room found (and gives it to the engine) when it differs from the one shown by more
// than the estimate's own noise: a corner 2 cm, the ceiling 1 cm, or another corner count.
void CoarseRoomModel::apply_found_room(const FoundRoom &p_found, const Pose &p_world_from_model) {
	const RoomEstimate &estimate = p_found.result.estimate;
	const Pose placed = compose(p_world_from_model, inverse(estimate.world_from_model)); // the world from the room found
	const std::vector<Vec2> &points = estimate.floorplan.points;
	bool changed = !found || int64_t(points.size()) != floorplan.size() || std::abs(estimate.floorplan.ceiling_height_m - ceiling_height) > 0.01;
	const Pose shown_pose = world_from_room();
	for (size_t i = 0; !changed && i < points.size(); i++) {
		const glm::dvec3 now = transform_point(placed, glm::dvec3(points[i].x, 0.0, points[i].y));
		const glm::dvec3 before = transform_point(shown_pose, glm::dvec3(floorplan[int64_t(i)].x, 0.0, floorplan[int64_t(i)].y));
		changed = glm::length(now - before) > 0.02;
	}
	wall_confidence.resize(int64_t(estimate.edge_confidence.size()));
	for (size_t i = 0; i < estimate.edge_confidence.size(); i++) {
		wall_confidence[int64_t(i)] = float(estimate.edge_confidence[i]);
	}
	if (!changed) {
		return;
	}
	PackedVector2Array plan;
	for (const Vec2 &p : points) {
		plan.push_back(Vector2(real_t(p.x), real_t(p.y)));
	}
	floorplan = plan;
	ceiling_height = estimate.floorplan.ceiling_height_m;
	if (is_inside_tree()) {
		set_global_transform(transform_from_pose(placed));
	}
	rebuild();
	notify_property_list_changed();
}

PackedFloat32Array CoarseRoomModel::get_wall_confidence() const { return wall_confidence; }

bool CoarseRoomModel::find_room_in_recording(const String &p_path) {
	ERR_FAIL_COND_V_MSG(search != nullptr, false, "find_room_in_recording: a search is already running.");
	String path = p_path;
	if (path.is_empty()) {
		std::string unused;
		Node *capture = is_inside_tree() ? find_collaborator(*this, rig_capture_path, "RigCapture", "rig_capture", &unused) : nullptr;
		ERR_FAIL_COND_V_MSG(capture == nullptr, false, "find_room_in_recording: no path given and no RigCapture to take its recording_path from.");
		path = capture->get("recording_path");
	}
	std::string error;
	const std::string folder = disk_path_for(path, &error);
	ERR_FAIL_COND_V_MSG(!error.empty() || folder.empty(), false, String(("find_room_in_recording: " + (error.empty() ? std::string("the recording path is empty") : error)).c_str()));
	search = std::make_unique<RoomSearch>();
	search->recording = folder;
	RoomSearch *job = search.get();
	job->thread = std::thread([job] {
		RoomSweepOptions options;
		options.recording = job->recording;
		options.cancel = &job->cancel;
		try {
			job->result = sweep_room(options);
		} catch (const std::exception &e) {
			job->result = RoomSweepResult();
			job->result.error = job->recording + ": " + e.what();
		}
		job->done = true;
	});
	set_process(true); // in the editor too, until the room is taken
	return true;
}

bool CoarseRoomModel::is_finding_room() const { return search != nullptr; }

void CoarseRoomModel::stop_room_search() {
	if (search) {
		search->cancel = true;
		if (search->thread.joinable()) {
			search->thread.join();
		}
		search.reset();
	}
}

bool CoarseRoomModel::finish_room_search() {
	if (search && search->thread.joinable()) {
		search->thread.join();
	}
	take_room_search();
	return searched && searched->result.has_room;
}

void CoarseRoomModel::take_room_search() {
	if (!search || !search->done) {
		return;
	}
	if (search->thread.joinable()) {
		search->thread.join();
	}
	const RoomSweepResult result = std::move(search->result);
	search.reset();
	if (Engine::get_singleton()->is_editor_hint()) {
		set_process(false);
	}
	auto taken = std::make_shared<FoundRoom>();
	taken->version = searched ? searched->version + 1 : 1;
	taken->result.estimate = result.estimate;
	taken->result.fisheye_ceiling = result.fisheye_ceiling;
	taken->result.fisheye_walls = result.fisheye_walls;
	taken->result.has_room = !result.room.floorplan.points.empty();
	taken->result.initial_rgb_pose = result.room.initial_rgb_pose;
	if (!result.ok) {
		taken->result.estimate.message = result.error;
	}
	searched = taken;
	const RoomEstimate &estimate = taken->result.estimate;
	if (taken->result.has_room) {
		// The scene's world is the recording's: its first camera at room.yaml's initial_rgb_pose.
		apply_found_room(*taken, result.has_truth ? result.true_world_from_model : Pose());
		found = taken;
	}
	emit_signal("room_estimated", String(result.ok ? room_estimate_state_name(estimate.state) : "failed"), String(estimate.message.c_str()));
	update_configuration_warnings();
}

Dictionary CoarseRoomModel::get_room_estimate() const {
	Dictionary d;
	std::shared_ptr<const FoundRoom> newest = engine && !own_engine ? engine->found_room() : nullptr;
	if (!newest) {
		newest = searched;
	}
	if (!newest) {
		return d;
	}
	const RoomEstimate &estimate = newest->result.estimate;
	d.set("state", String(room_estimate_state_name(estimate.state)));
	d.set("message", String(estimate.message.c_str()));
	d.set("version", int64_t(newest->version));
	d.set("has_room", newest->result.has_room);
	d.set("ceiling_source", String(estimate.ceiling_source.c_str()));
	d.set("fused_frames", int64_t(newest->fused_frames));
	d.set("fisheye_views", int64_t(newest->fisheye_views));
	d.set("seconds", newest->seconds);
	return d;
}

bool CoarseRoomModel::estimate_room_now() {
	ERR_FAIL_COND_V_MSG(floorplan_source != FLOORPLAN_AUTOMATIC, false, "estimate_room_now() needs floorplan_source Automatic.");
	ERR_FAIL_COND_V_MSG(!engine || own_engine, false, "estimate_room_now() needs a RigCapture with DenseSLAM (the room is found in the dense model).");
	engine->apply_config(); // find_room on before the estimate
	engine->find_room_now();
	take_found_room();
	return found != nullptr;
}

} // namespace roomprobe
