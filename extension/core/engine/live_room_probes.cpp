#include "live_room_internal.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace roomprobe {

using namespace live_room_detail;

// ---------------------------------------------------------------- probes

int LiveRoom::add_probe(const glm::dvec3 &p_position, int p_size) {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	auto probe = std::make_shared<Probe>();
	probe->position = p_position;
	probe->size = std::clamp(p_size, 1, 4096);
	const int id = next_probe++;
	probes[id] = probe;
	probes_dirty.notify_all();
	return id;
}

void LiveRoom::set_probe(int p_probe, const glm::dvec3 &p_position, int p_size) {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	const auto it = probes.find(p_probe);
	if (it == probes.end()) {
		return;
	}
	const int size = std::clamp(p_size, 1, 4096);
	if (it->second->position != p_position || it->second->size != size) {
		it->second->position = p_position;
		it->second->size = size;
		it->second->dirty = true;
		probes_dirty.notify_all();
	}
}

void LiveRoom::set_probe_objects(int p_probe, std::shared_ptr<const VirtualScene> p_objects) {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	const auto it = probes.find(p_probe);
	if (it == probes.end() || it->second->objects == p_objects) {
		return;
	}
	it->second->objects = std::move(p_objects);
	it->second->dirty = true;
	probes_dirty.notify_all();
}

void LiveRoom::remove_probe(int p_probe) {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	probes.erase(p_probe);
}

std::vector<glm::dvec3> LiveRoom::probe_positions() const {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	std::vector<glm::dvec3> positions;
	for (const auto &[id, probe] : probes) {
		positions.push_back(probe->position);
	}
	return positions;
}

std::shared_ptr<const ProbeMap> LiveRoom::probe_map(int p_probe) const {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	const auto it = probes.find(p_probe);
	return it == probes.end() ? nullptr : it->second->map;
}

void LiveRoom::render_probes() {
	std::vector<std::tuple<int, glm::dvec3, int>> jobs;
	uint64_t generation = 0;
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		for (auto &[id, probe] : probes) {
			jobs.emplace_back(id, probe->position, probe->size);
			probe->dirty = false;
		}
		generation = input_generation;
	}
	for (const auto &[id, position, size] : jobs) {
		render_one(id, position, size, generation);
	}
}

bool LiveRoom::render_probe(int p_probe) {
	glm::dvec3 position;
	int size = 0;
	uint64_t generation = 0;
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		const auto it = probes.find(p_probe);
		if (it == probes.end()) {
			return false;
		}
		position = it->second->position;
		size = it->second->size;
		it->second->dirty = false;
		generation = input_generation;
	}
	return render_one(p_probe, position, size, generation) != nullptr;
}

bool LiveRoom::probe_is_current(int p_probe) const {
	const std::lock_guard<std::mutex> lock(probe_mutex);
	const auto it = probes.find(p_probe);
	return it != probes.end() && it->second->map && !it->second->dirty && it->second->rendered_generation >= input_generation;
}

CoarseMapInput LiveRoom::coarse_input(const CoarseSnapshot &p_snapshot) {
	CoarseMapInput input;
	input.atlas = p_snapshot.atlas;
	input.observed = p_snapshot.observed;
	input.cumulative = p_snapshot.cumulative;
	input.published = true; // a snapshot's Mats are never written after publishing
	return input;
}

DenseMapInput LiveRoom::dense_input(bool p_with_dense) {
	DenseMapInput input;
	if (p_with_dense && slam) {
		input.slam = slam.get();
		input.lighting = &dense_lighting;
	}
	return input;
}

std::shared_ptr<const ProbeMap> LiveRoom::render_one(int p_probe, const glm::dvec3 &p_position, int p_size, uint64_t p_generation) {
	if (!renderer) {
		return nullptr; // not configured
	}
	try {
		const double start = now_s();
		std::shared_ptr<const CoarseSnapshot> snapshot;
		std::shared_ptr<const TrackedFrame> frame;
		{
			const std::lock_guard<std::mutex> lock(publish_mutex);
			snapshot = last_coarse;
			frame = last_tracked;
		}
		std::shared_ptr<Probe> probe;
		std::shared_ptr<const VirtualScene> objects; // the other virtual objects to draw
		std::shared_ptr<const ProbeMap> previous; // the probe's last map: their light
		{
			const std::lock_guard<std::mutex> lock(probe_mutex);
			const auto it = probes.find(p_probe);
			if (it != probes.end()) {
				probe = it->second;
				objects = probe->objects;
				previous = probe->map;
				if (p_generation >= full_faces_generation) {
					probe->dense_faces.refresh_all = true;
				}
			}
		}
		auto map = std::make_shared<ProbeMap>();
		map->probe = p_probe;
		map->position = p_position;
		map->rgbd_sequence = frame ? frame->sequence : 0;
		map->fisheye_sequence = snapshot ? snapshot->fisheye_sequence : 0;
		const CoarseMapInput coarse_part = snapshot ? coarse_input(*snapshot) : CoarseMapInput();
		renderer->render_map(p_size, snapshot ? &coarse_part : nullptr, dense_input(true), objects.get(), previous.get(), probe ? &probe->dense_faces : nullptr,
				map.get());
		map->total_ms = ms_since(start);
		if (renderer->gpu_failures() > 0) {
			const std::string problem = renderer->gpu_problem();
			const std::lock_guard<std::mutex> lock(stats_mutex);
			compute_note = compute_backend_note(cfg.compute_backend, nullptr, problem);
			compute_on_device = false;
		}
		{
			const std::lock_guard<std::mutex> lock(probe_mutex);
			const auto it = probes.find(p_probe);
			if (it == probes.end()) {
				return nullptr; // removed meanwhile
			}
			map->version = ++it->second->version;
			it->second->map = map;
			it->second->rendered_generation = std::max(it->second->rendered_generation, p_generation);
		}
		note_latency(*map);
		return map;
	} catch (const std::exception &e) {
		record_error("probe rendering", e.what());
		return nullptr;
	}
}

void LiveRoom::note_latency(const ProbeMap &p_map) {
	const double now = now_s();
	const std::lock_guard<std::mutex> lock(stats_mutex);
	counters.probe_renders++;
	auto note = [now](uint64_t p_sequence, uint64_t *io_seen, const std::vector<std::pair<uint64_t, double>> &p_arrivals, std::vector<double> *r_series) {
		if (p_sequence == 0 || p_sequence <= *io_seen) {
			return;
		}
		*io_seen = p_sequence;
		for (const auto &[sequence, arrival] : p_arrivals) {
			if (sequence == p_sequence) {
				r_series->push_back((now - arrival) * 1000.0);
				return;
			}
		}
	};
	note(p_map.rgbd_sequence, &rgbd_latency_seen, rgbd_arrivals, &rgbd_latencies_ms);
	note(p_map.fisheye_sequence, &fisheye_latency_seen, fisheye_arrivals, &fisheye_latencies_ms);
}

Cubemap LiveRoom::render_at(const glm::dvec3 &p_position, int p_size, bool p_completed, bool p_with_dense, DenseRenderStats *r_dense) {
	if (!configured || p_size < 1 || p_size > 4096) {
		return Cubemap();
	}
	std::shared_ptr<const CoarseSnapshot> snapshot;
	{
		const std::lock_guard<std::mutex> lock(publish_mutex);
		snapshot = last_coarse;
	}
	CoarseMapInput source = snapshot ? coarse_input(*snapshot) : CoarseMapInput();
	if (!p_completed && coarse && !running) {
		// The observations alone (no inpainting), straight from the pipeline: nothing writes it now.
		source.atlas = coarse->texture().color;
		source.observed = cfg.coarse_shell_first ? observed_mask(coarse->texture(), coarse->rgb_only()) : cv::Mat();
		source.cumulative = coarse->cumulative_lighting();
		source.published = false; // the pipeline's own, which it writes again
	}
	DenseRenderStats dense;
	double coarse_ms = 0.0, dense_ms = 0.0;
	Cubemap map = renderer->render_faces(p_position, p_size, &source, dense_input(p_with_dense), &dense, &coarse_ms, &dense_ms);
	if (r_dense != nullptr) {
		*r_dense = dense;
	}
	return map;
}

// ---------------------------------------------------------------- results

std::shared_ptr<const TrackedFrame> LiveRoom::tracked_frame() const {
	const std::lock_guard<std::mutex> lock(publish_mutex);
	return last_tracked;
}

std::shared_ptr<const CoarseSnapshot> LiveRoom::coarse_snapshot() const {
	const std::lock_guard<std::mutex> lock(publish_mutex);
	return last_coarse;
}

std::shared_ptr<const DenseMeshSnapshot> LiveRoom::dense_mesh() const {
	const std::lock_guard<std::mutex> lock(publish_mutex);
	return last_mesh;
}

void LiveRoom::send_mesh_input() {
	if (!slam) {
		return;
	}
	const std::shared_ptr<DenseMeshStage::Input> input = mesh_stage.copy_changed(*slam);
	if (running) {
		mesh_inputs.put(input);
	} else {
		mesh_and_publish(*input);
	}
}

void LiveRoom::mesh_and_publish(DenseMeshStage::Input &p_input) {
	bool changed = false;
	const std::shared_ptr<DenseMeshSnapshot> snapshot = mesh_stage.mesh(p_input, &changed);
	{
		const std::lock_guard<std::mutex> lock(publish_mutex);
		snapshot->version = last_mesh ? last_mesh->version + 1 : 1;
		last_mesh = snapshot;
	}
	if (changed) {
		place_on(*snapshot->mesh);
	}
}

void LiveRoom::update_dense_mesh() {
	if (running || !slam) {
		return; // the SLAM and mesh workers mesh while running
	}
	send_mesh_input();
}

Trajectory LiveRoom::trajectory() const {
	return tracked.copy();
}

const RoomMesh *LiveRoom::room_mesh() const {
	return coarse ? &coarse->mesh() : own_room.get();
}

double LiveRoom::distance_outside_room_m(const glm::dvec3 &p_world) const {
	const RoomMesh *mesh = room_mesh();
	if (mesh == nullptr) {
		return 0.0;
	}
	const glm::dvec3 room = transform_point(inverse(cfg.world_from_room), p_world);
	return roomprobe::distance_outside_room_m(mesh->floorplan, Vec3{ room.x, room.y, room.z });
}

PlacementHit LiveRoom::place_ray(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_max_distance_m) const {
	const std::lock_guard<std::mutex> lock(placer_mutex);
	return placer.cast(p_origin, p_direction, p_max_distance_m);
}

void LiveRoom::finish() {
	if (running) {
		// Until both workers have taken every posted frame and finished it (at most 30 s).
		for (int i = 0; i < 6000; i++) {
			if (!frames->rgbd_outstanding() && !frames->fisheye_outstanding()) {
				break;
			}
			std::this_thread::sleep_for(std::chrono::milliseconds(5));
		}
	}
	if (!coarse) {
		return;
	}
	if (running && coarse->rgb_only()) {
		// The last view offered, which the coarse worker may not have taken yet.
		if (std::optional<PendingRgb> view = take_rgb_view(std::chrono::milliseconds(0))) {
			process_rgb_view(*view);
		}
	}
	{
		const std::lock_guard<std::mutex> coarse_lock(coarse_mutex);
		coarse->finish_inpainting();
		const std::lock_guard<std::mutex> lock(publish_mutex);
		if (last_coarse) {
			auto snapshot = std::make_shared<CoarseSnapshot>(*last_coarse);
			snapshot->set_atlas(coarse->completed_color().clone(), cfg.display_buffers);
			last_coarse = snapshot;
		}
	}
	if (!running) {
		return;
	}
	// Threaded: a render that started before the last snapshot may still be finishing. Wait until
	// every probe has a map rendered from inputs at least this new (at most 10 s).
	uint64_t generation = 0;
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		inputs_changed = true;
		generation = ++input_generation;
		full_faces_generation = generation; // the final maps raycast every dense face
	}
	probes_dirty.notify_all();
	for (int i = 0; i < 2000; i++) {
		{
			const std::lock_guard<std::mutex> lock(probe_mutex);
			if (std::all_of(probes.begin(), probes.end(), [generation](const auto &p_entry) { return p_entry.second->rendered_generation >= generation; })) {
				break;
			}
		}
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
}

LiveRoomStats LiveRoom::stats() const {
	LiveRoomStats s;
	{
		const std::lock_guard<std::mutex> lock(stats_mutex);
		s = counters;
		s.compute = compute_note;
		s.compute_on_device = compute_on_device;
		s.rgbd_latency = summarise_latency(rgbd_latencies_ms);
		s.fisheye_latency = summarise_latency(fisheye_latencies_ms);
	}
	s.running = running;
	s.rgbd_dropped = frames->rgbd.dropped_count();
	s.fisheye_dropped = frames->fisheye.dropped_count();
	if (slam) {
		const std::string slam_problem = slam->compute_problem();
		if (!slam_problem.empty() && s.compute_on_device) {
			s.compute += "; " + slam_problem;
			s.compute_on_device = false;
		}
		s.dense_frames = slam->frame_count();
		s.dense_fused = slam->integrated_count();
		s.relocalisation_attempts = slam->relocalisation_attempts();
		s.relocalisations = slam->relocalisation_count();
		s.keyframes = slam->keyframe_count();
		s.keyframe_relocalisations = slam->keyframe_relocalisation_count();
	}
	return s;
}

const DenseSlam *LiveRoom::slam_model() const {
	return running ? nullptr : slam.get();
}

const CoarsePipeline *LiveRoom::coarse_model() const {
	return running ? nullptr : coarse.get();
}

} // namespace roomprobe
