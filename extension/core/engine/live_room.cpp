#include "live_room_internal.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace roomprobe {

using namespace live_room_detail;

LatencySummary summarise_latency(std::vector<double> p_values) {
	LatencySummary s;
	s.count = p_values.size();
	if (p_values.empty()) {
		return s;
	}
	std::sort(p_values.begin(), p_values.end());
	auto rank = [&](double p_fraction) {
		const size_t r = size_t(std::ceil(p_fraction * double(p_values.size())));
		return p_values[std::min(p_values.size() - 1, r > 0 ? r - 1 : 0)];
	};
	s.p50_ms = rank(0.5);
	s.p95_ms = rank(0.95);
	s.max_ms = p_values.back();
	return s;
}

LiveRoom::LiveRoom() :
		frames(std::make_unique<Frames>()) {}

LiveRoom::~LiveRoom() {
	stop();
}

// ---------------------------------------------------------------- configuration

LiveRoomConfig LiveRoom::config() const {
	return cfg;
}

std::string LiveRoom::configuration_error() const {
	return config_error;
}

std::string LiveRoom::configure(const LiveRoomConfig &p_config) {
	const std::unique_lock<std::shared_mutex> exclusive(lifecycle);
	{
		const std::lock_guard<std::mutex> lock(pending_mutex);
		pending = p_config;
		has_pending = false;
	}
	return configure_locked(p_config);
}

void LiveRoom::edit_config(const std::function<void(LiveRoomConfig &)> &p_edit) {
	const std::lock_guard<std::mutex> lock(pending_mutex);
	if (!has_pending) {
		pending = cfg;
		has_pending = true;
	}
	p_edit(pending);
}

bool LiveRoom::config_pending() const {
	const std::lock_guard<std::mutex> lock(pending_mutex);
	return has_pending;
}

std::string LiveRoom::apply_config() {
	const std::unique_lock<std::shared_mutex> exclusive(lifecycle);
	LiveRoomConfig next;
	{
		const std::lock_guard<std::mutex> lock(pending_mutex);
		if (!has_pending) {
			return config_error;
		}
		next = pending;
		has_pending = false;
	}
	const bool was_running = running;
	const std::string error = configure_locked(next);
	if (error.empty() && was_running) {
		start_locked();
	}
	return error;
}

bool LiveRoom::set_atlas(const cv::Mat &p_atlas) {
	const RoomMesh *mesh = room_mesh();
	if (mesh == nullptr || p_atlas.type() != CV_32FC3 || p_atlas.cols != mesh->atlas_width || p_atlas.rows != mesh->atlas_height) {
		return false;
	}
	auto snapshot = std::make_shared<CoarseSnapshot>();
	snapshot->set_atlas(p_atlas.clone(), cfg.display_buffers);
	snapshot->cumulative.valid = true;
	{
		const std::lock_guard<std::mutex> lock(publish_mutex);
		last_coarse = snapshot;
	}
	wake_probes();
	return true;
}

// The room's part of the configuration (cfg): the coarse pipeline (or, without a rig, the room
// mesh alone), its renderer and the placement scene. Workers stopped. The error names the problem.
std::string LiveRoom::build_room_locked() {
	coarse.reset();
	own_room.reset();
	renderer.reset();
	if (cfg.has_room && !cfg.has_rig) {
		RoomMeshOptions mesh_options;
		mesh_options.texel_size_m = cfg.coarse.texel_size_m;
		RoomMeshResult built = build_room_mesh(cfg.floorplan, mesh_options);
		if (!built.ok) {
			return "room: " + built.error;
		}
		own_room = std::make_unique<RoomMesh>(std::move(built.mesh));
	} else if (cfg.has_room) {
		CoarsePipelineOptions options = cfg.coarse;
		options.pose_source = cfg.coarse_poses;
		if (linearizer.active()) {
			// Clipped pixels come with the frame's saturation mask, which the texture update
			// keeps out of the lighting pairs; black in linearised units: the centre pixel's 5
			// at the reference exposure.
			options.lighting_options.saturated_threshold = std::numeric_limits<float>::infinity();
			options.lighting_options.black_threshold = linearizer.centre_radiance(5);
		}
		auto fresh = std::make_unique<CoarsePipeline>(options);
		const std::string error = fresh->configure(cfg.rig, cfg.floorplan);
		if (!error.empty()) {
			return error;
		}
		coarse = std::move(fresh);
	}
	ProbeRenderSettings settings;
	settings.world_from_room = cfg.world_from_room;
	settings.coarse_shell_first = cfg.coarse_shell_first;
	settings.dense_scale = cfg.dense_render_scale;
	settings.dense_far_m = cfg.dense_render_far_m;
	settings.dense_faces_per_render = cfg.dense_faces_per_render;
	settings.rgb_lut = rgb_lut;
	settings.rgb_lut_active = rgb_lut_active;
	settings.wait_for_ggx_filter = cfg.wait_for_ggx_filter;
	settings.face_buffers = cfg.display_buffers;
	std::string reason;
	settings.compute = shared_compute_device(cfg.compute_backend, &reason);
	{
		const std::lock_guard<std::mutex> lock(stats_mutex);
		compute_note = compute_backend_note(cfg.compute_backend, settings.compute.get(), reason);
		compute_on_device = settings.compute != nullptr;
	}
	renderer = std::make_unique<ProbeRenderer>(room_mesh(), settings);
	room_builds++;
	const std::lock_guard<std::mutex> lock(placer_mutex);
	placer.clear_coarse();
	if (room_mesh() != nullptr) {
		const std::string error = placer.set_coarse(*room_mesh(), cfg.world_from_room);
		if (!error.empty()) {
			return "placement: " + error;
		}
	}
	return "";
}

std::string LiveRoom::configure_locked(const LiveRoomConfig &p_config) {
	stop_locked();
	configured = false;
	slam.reset();
	renderer.reset();
	coarse.reset();
	own_room.reset();
	cfg = p_config;
	auto fail = [this](const std::string &p_error) {
		config_error = p_error;
		return p_error;
	};
	try {
		if (!cfg.dense && !cfg.has_room) {
			return fail("nothing to model: no room (floorplan) and dense SLAM off");
		}
		if (cfg.coarse_poses == PoseSource::Tracked && cfg.has_room && cfg.has_rig && !cfg.dense) {
			return fail("the coarse model takes tracked poses, but dense SLAM is off: use ground-truth poses or turn dense SLAM on");
		}
		if ((cfg.coarse_poses == PoseSource::GroundTruth && cfg.has_room && cfg.has_rig) || (cfg.dense_poses == PoseSource::GroundTruth && cfg.dense)) {
			if (cfg.ground_truth.is_empty()) {
				return fail("ground-truth poses were asked for, but there is no ground-truth RGB-D trajectory");
			}
		}
		if (cfg.mesh_interval_frames < 1 || !(cfg.fisheye_extrapolation_s >= 0.0) || !(cfg.fisheye_pose_wait_s >= 0.0) || cfg.render_threads < 1 ||
				cfg.dense_render_scale < 1) {
			return fail("mesh_interval_frames, render_threads and dense_render_scale must be >= 1, the fisheye times >= 0");
		}
		if (!cfg.has_rig && cfg.dense) {
			return fail("dense SLAM needs a rig (RigCapture with a recording or devices)");
		}
		const std::string rig_error = cfg.has_rig ? check_rig(cfg.rig) : "";
		if (!rig_error.empty()) {
			return fail("rig: " + rig_error);
		}
		linearizer.configure(cfg.photometry, cfg.rig.fisheye);
		{
			const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
			pending_rgb.reset(); // a frame of the old configuration
			next_rgb_view_s = -std::numeric_limits<double>::infinity();
		}
		rgb_lut_active = cfg.photometry.known;
		rgb_lut = rgb_radiance_lut(cfg.photometry);
		if (cfg.dense) {
			DenseSlamOptions slam_options = cfg.slam;
			if (cfg.find_room) { // the room's far walls matter to finding it (room/room_from_sweep.h)
				slam_options.tsdf.max_depth_m = std::max(slam_options.tsdf.max_depth_m, FIND_ROOM_MAX_DEPTH_M);
			}
			auto fresh = std::make_unique<DenseSlam>(slam_options);
			const std::string error = fresh->configure(cfg.rig.rgb, cfg.initial_rgb_pose);
			if (!error.empty()) {
				return fail("dense SLAM: " + error);
			}
			fresh->volume().set_keep_points(cfg.keep_points);
			std::string no_device; // said by the note build_room_locked makes
			fresh->set_compute(shared_compute_device(cfg.compute_backend, &no_device)); // its failure: stats().compute
			slam = std::move(fresh);
		}
		{
			const std::lock_guard<std::mutex> lock(placer_mutex);
			placer = SurfacePlacer();
		}
		const std::string room_error = build_room_locked();
		if (!room_error.empty()) {
			return fail(room_error);
		}
	} catch (const std::exception &e) {
		return fail(std::string("configuring the live room failed: ") + e.what());
	}
	{
		tracked.clear();
	}
	{
		room_finder.reset();
	}
	dense_lighting.reset();
	{
		const std::lock_guard<std::mutex> lock(publish_mutex);
		last_tracked.reset();
		last_coarse.reset();
		last_mesh.reset();
		fused_since_mesh = 0;
		remesh_due = false;
	}
	mesh_stage.clear();
	mesh_inputs.reopen();
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		for (auto &[id, probe] : probes) {
			probe->dirty = true;
			probe->map.reset();
		}
	}
	{
		const std::lock_guard<std::mutex> lock(stats_mutex);
		counters = LiveRoomStats();
		rgbd_latencies_ms.clear();
		fisheye_latencies_ms.clear();
		rgbd_arrivals.clear();
		fisheye_arrivals.clear();
		rgbd_latency_seen = fisheye_latency_seen = 0;
	}
	frames->rgbd.reopen();
	frames->fisheye.reopen();
	frames->rgbd_done = 0;
	frames->fisheye_done = 0;
	config_error.clear();
	configured = true;
	return "";
}

std::string LiveRoom::reconfigure(const std::function<void(LiveRoomConfig &)> &p_edit) {
	edit_config(p_edit);
	return apply_config();
}

// ---------------------------------------------------------------- threads

bool LiveRoom::start() {
	const std::unique_lock<std::shared_mutex> exclusive(lifecycle);
	return start_locked();
}

void LiveRoom::stop() {
	const std::unique_lock<std::shared_mutex> exclusive(lifecycle);
	stop_locked();
}

bool LiveRoom::start_locked() {
	if (running) {
		return true;
	}
	if (!configured || !cfg.has_rig) {
		return false;
	}
	stopping = false;
	// The counts go on from configure(), so that pushed = processed + dropped over stops and starts.
	frames->rgbd.open();
	frames->fisheye.open();
	running = true;
	slam_thread = std::thread([this] { slam_worker(); });
	coarse_thread = std::thread([this] { coarse_worker(); });
	probe_thread = std::thread([this] { probe_worker(); });
	if (cfg.find_room && slam) {
		room_thread = std::thread([this] { room_worker(); });
	}
	mesh_inputs.open();
	mesh_thread = std::thread([this] { mesh_worker(); });
	return true;
}

void LiveRoom::stop_locked() {
	if (!running) {
		return;
	}
	stopping = true;
	frames->rgbd.close();
	frames->fisheye.close();
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		probes_dirty.notify_all();
	}
	{
		const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
		pending_rgb_ready.notify_all();
	}
	{
		tracked.wake_all();
	}
	room_finder.wake();
	mesh_inputs.close();
	for (std::thread *t : { &slam_thread, &coarse_thread, &probe_thread, &room_thread, &mesh_thread }) {
		if (t->joinable()) {
			t->join();
		}
	}
	// Blocks copied after the mesh worker's last take are meshed here.
	if (std::optional<std::shared_ptr<DenseMeshStage::Input>> input = mesh_inputs.try_take()) {
		mesh_and_publish(**input);
	}
	running = false;
}

void LiveRoom::slam_worker() {
	while (!stopping) {
		std::optional<Frames::Rgbd> item = frames->rgbd.take(WORKER_POLL);
		if (!item) {
			continue;
		}
		process_rgbd(item->frame, item->sequence);
		frames->rgbd_done++;
	}
}

void LiveRoom::coarse_worker() {
	const bool rgb_only = coarse && coarse->rgb_only();
	while (!stopping) {
		if (rgb_only) {
			if (std::optional<PendingRgb> view = take_rgb_view(WORKER_POLL)) {
				process_rgb_view(*view);
			}
			continue;
		}
		std::optional<Frames::Fisheye> item = frames->fisheye.take(WORKER_POLL);
		if (!item) {
			continue;
		}
		process_fisheye(item->frame, item->sequence, true);
		frames->fisheye_done++;
	}
}

void LiveRoom::probe_worker() {
	tbb::task_arena arena(std::max(1, cfg.render_threads));
	while (!stopping) {
		std::vector<std::tuple<int, glm::dvec3, int>> jobs;
		uint64_t generation = 0;
		{
			std::unique_lock<std::mutex> lock(probe_mutex);
			probes_dirty.wait_for(lock, WORKER_POLL, [this] {
				if (stopping || inputs_changed) {
					return true;
				}
				return std::any_of(probes.begin(), probes.end(), [](const auto &p_entry) { return p_entry.second->dirty; });
			});
			if (stopping) {
				break;
			}
			for (auto &[id, probe] : probes) {
				if (inputs_changed || probe->dirty) {
					jobs.emplace_back(id, probe->position, probe->size);
					probe->dirty = false;
				}
			}
			inputs_changed = false;
			generation = input_generation;
		}
		for (const auto &[id, position, size] : jobs) {
			if (stopping) {
				break;
			}
			arena.execute([&, id = id, position = position, size = size] { render_one(id, position, size, generation); });
		}
	}
}

// Meshes the blocks the SLAM worker copied, then builds the placement scene, off the SLAM
// worker: on a room's mesh marching cubes take about 100 ms and the Embree build hundreds more,
// and a frame waiting behind them would be dropped.
void LiveRoom::mesh_worker() {
	while (!stopping) {
		if (std::optional<std::shared_ptr<DenseMeshStage::Input>> input = mesh_inputs.take(WORKER_POLL)) {
			mesh_and_publish(**input);
		}
	}
}

// The placement scene from p_mesh, built outside placer_mutex so that cast never waits for it.
void LiveRoom::place_on(const TriangleMesh &p_mesh) {
	std::shared_ptr<const EmbreeTriangleScene> scene;
	const std::string error = SurfacePlacer::build_dense(p_mesh, &scene);
	if (!error.empty()) {
		record_error("placement", error);
		return;
	}
	const std::lock_guard<std::mutex> lock(placer_mutex);
	placer.set_dense_scene(std::move(scene));
}

void LiveRoom::wake_probes() {
	{
		const std::lock_guard<std::mutex> lock(probe_mutex);
		inputs_changed = true;
		input_generation++;
	}
	probes_dirty.notify_all();
}

} // namespace roomprobe
