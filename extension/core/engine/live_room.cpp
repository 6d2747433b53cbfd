#include "live_room.h"

#include <envmap/ggx_prefilter.h>
#include <envmap/spherical_harmonics.h>
#include <rig/fisheye_pose.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <limits>
#include <chrono>
#include <cmath>
#include <cstring>

namespace roomprobe {

namespace {

using Clock = std::chrono::steady_clock;

double now_s() {
	return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

double ms_since(double p_start_s) {
	return (now_s() - p_start_s) * 1000.0;
}

// How long a worker waits on an empty mailbox before it looks at the stop flag again.
constexpr std::chrono::milliseconds WORKER_POLL(50);
// Arrival times kept for the latency figures (frames older than this many are forgotten).
constexpr size_t ARRIVALS_KEPT = 256;

// One face as Godot's RGBAH image with mipmaps wants it: level 0, then each half-size level down
// to 1x1, RGBA half floats. The levels are the GGX chain's (ggx_prefilter.h), then box halvings
// of its last level, which no shader reads for roughness.
std::vector<uint16_t> gpu_face(const std::vector<Cubemap> &p_chain, const cv::Mat &p_distance_m, int p_face) {
	std::vector<uint16_t> out;
	cv::Mat level, distance = p_distance_m;
	for (size_t m = 0;; m++) {
		if (m < p_chain.size()) {
			level = p_chain[m].faces[size_t(p_face)];
		} else {
			cv::Mat next;
			cv::resize(level, next, cv::Size(std::max(1, level.cols / 2), std::max(1, level.rows / 2)), 0.0, 0.0, cv::INTER_AREA);
			level = next;
		}
		const cv::Size size = level.size();
		// Alpha: the distance to the surface each texel shows (envmap/parallax.h), area-averaged
		// down the chain; 0 where the map has none.
		if (distance.empty()) {
			distance = cv::Mat(size, CV_32FC1, cv::Scalar(0.0f));
		} else if (distance.size() != size) {
			cv::Mat next;
			cv::resize(distance, next, size, 0.0, 0.0, cv::INTER_AREA);
			distance = next;
		}
		cv::Mat rgba, half;
		const cv::Mat channels[2] = { level, distance };
		rgba.create(level.size(), CV_32FC4);
		const int pairs[8] = { 0, 0, 1, 1, 2, 2, 3, 3 };
		cv::mixChannels(channels, 2, &rgba, 1, pairs, 4);
		rgba.convertTo(half, CV_16F);
		const size_t n = size_t(half.total()) * 4;
		const size_t at = out.size();
		out.resize(at + n);
		for (int y = 0; y < half.rows; y++) {
			std::memcpy(out.data() + at + size_t(y) * size_t(half.cols) * 4, half.ptr(y), size_t(half.cols) * 4 * sizeof(uint16_t));
		}
		if (level.cols == 1 && level.rows == 1) {
			break;
		}
	}
	return out;
}

// CoarseSnapshot::observed of a texture: where the fisheye observed each texel.
cv::Mat observed_mask(const CoarseTexture &p_texture) {
	cv::Mat observed;
	if (p_texture.quality.empty()) {
		return observed;
	}
	cv::Mat(p_texture.quality > 0.0f).convertTo(observed, CV_32F, 1.0 / 255.0); // 255 or 0 -> 1 or 0
	return observed;
}

} // namespace

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

struct LiveRoom::Probe {
	glm::dvec3 position = glm::dvec3(0.0);
	int size = 128;
	bool dirty = true; // moved, resized or new since its last map
	uint64_t version = 0;
	uint64_t rendered_generation = 0; // the input_generation its newest map was rendered from
	std::shared_ptr<const ProbeMap> map;
	DenseFaceCache dense_faces; // its dense faces between maps
	std::shared_ptr<const VirtualScene> objects; // drawn over the room (may be null)
};

struct LiveRoom::Frames {
	struct Rgbd {
		RgbdFrame frame;
		uint64_t sequence = 0;
	};
	struct Fisheye {
		FisheyeFrame frame;
		uint64_t sequence = 0;
	};
	Mailbox<Rgbd> rgbd;
	Mailbox<Fisheye> fisheye;
	// Frames a worker has finished. Every frame put is either dropped or finished, so
	// put - dropped - done is the work still to do, with no gap between a take and its start.
	std::atomic<uint64_t> rgbd_done{ 0 }, fisheye_done{ 0 };

	bool rgbd_outstanding() const { return rgbd.put_count() - rgbd.dropped_count() > rgbd_done; }
	bool fisheye_outstanding() const { return fisheye.put_count() - fisheye.dropped_count() > fisheye_done; }
};

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
	snapshot->atlas = p_atlas.clone();
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
		renderer = std::make_unique<CoarseCubemapRenderer>(*own_room);
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
		renderer = std::make_unique<CoarseCubemapRenderer>(coarse->mesh());
	}
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
		const std::lock_guard<std::mutex> lock(pose_mutex);
		tracked.clear();
	}
	{
		const std::lock_guard<std::mutex> lock(room_mutex);
		room_views.clear();
		room_view_spacing_s = 0.25;
		last_found.reset();
		found_mesh_version = 0;
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
		const std::lock_guard<std::mutex> lock(pose_mutex);
		pose_advanced.notify_all();
	}
	{
		const std::lock_guard<std::mutex> lock(room_mutex);
		room_wake.notify_all();
	}
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
	while (!stopping) {
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

// ---------------------------------------------------------------- frames in

void LiveRoom::push_rgbd(RgbdFrame p_frame) {
	const uint64_t sequence = ++rgbd_sequence;
	const double arrival = now_s();
	note_arrival(sequence, arrival, &counters.rgbd_pushed, &rgbd_arrivals);
	const std::shared_lock<std::shared_mutex> shared(lifecycle);
	if (running) {
		frames->rgbd.put(Frames::Rgbd{ std::move(p_frame), sequence });
	} else if (configured && cfg.has_rig) {
		process_rgbd(p_frame, sequence);
	}
}

void LiveRoom::push_fisheye(FisheyeFrame p_frame) {
	const uint64_t sequence = ++fisheye_sequence;
	const double arrival = now_s();
	note_arrival(sequence, arrival, &counters.fisheye_pushed, &fisheye_arrivals);
	const std::shared_lock<std::shared_mutex> shared(lifecycle);
	if (configured && cfg.has_rig && cfg.find_room) {
		keep_room_view(p_frame);
	}
	if (running) {
		frames->fisheye.put(Frames::Fisheye{ std::move(p_frame), sequence });
	} else if (configured && cfg.has_rig) {
		process_fisheye(p_frame, sequence, false);
	}
}

void LiveRoom::note_arrival(uint64_t p_sequence, double p_arrival_s, uint64_t *io_pushed, std::vector<std::pair<uint64_t, double>> *io_arrivals) {
	const std::lock_guard<std::mutex> lock(stats_mutex);
	(*io_pushed)++;
	io_arrivals->emplace_back(p_sequence, p_arrival_s);
	if (io_arrivals->size() > ARRIVALS_KEPT) {
		io_arrivals->erase(io_arrivals->begin());
	}
}

void LiveRoom::record_error(const std::string &p_stage, const std::string &p_what) {
	const std::lock_guard<std::mutex> lock(stats_mutex);
	counters.stage_errors++;
	counters.last_error = p_stage + ": " + p_what;
}

void LiveRoom::process_rgbd(const RgbdFrame &p_frame, uint64_t p_sequence) {
	try {
		auto out = std::make_shared<TrackedFrame>();
		out->sequence = p_sequence;
		out->timestamp_s = p_frame.timestamp_s;
		out->rgb = p_frame.rgb;
		bool fused = false;
		Pose truth;
		std::string truth_error;
		const bool has_truth = !cfg.ground_truth.is_empty() && cfg.ground_truth.pose_at(p_frame.timestamp_s, &truth, &truth_error);
		if (slam) {
			DenseSlamFrame result;
			if (cfg.dense_poses == PoseSource::GroundTruth) {
				if (has_truth) {
					result = slam->process_at_pose(p_frame, truth);
				} else {
					result.tracking.reason = "no ground-truth pose at this frame: " + truth_error;
				}
			} else {
				result = slam->process(p_frame);
			}
			out->state = result.tracking.state;
			out->reason = result.tracking.reason;
			out->integrated = result.integrated;
			out->inlier_fraction = result.tracking.inlier_fraction;
			out->rmse_m = result.tracking.rmse_m;
			out->constraint = result.tracking.constraint;
			out->colour_used = result.tracking.colour_used;
			out->relocalised = result.tracking.relocalised;
			out->timings = result.timings;
			out->has_pose = slam->integrated_count() > 0; // the model exists, so the pose means something
			out->world_from_camera = slam->pose();
			if (result.tracking.state != TrackingState::Lost && out->has_pose) {
				std::string error;
				{
					const std::lock_guard<std::mutex> lock(pose_mutex);
					tracked.append({ p_frame.timestamp_s, slam->pose() }, &error); // a repeated timestamp is skipped
				}
				pose_advanced.notify_all();
			}
			fused = result.integrated;
		} else if (has_truth) {
			// No SLAM: the AR view still follows the recording's true poses.
			out->has_pose = true;
			out->world_from_camera = truth;
			out->state = TrackingState::Good;
		}
		// The coarse model takes the texels its fisheye never saw from this frame, on its own
		// thread at its next fisheye frame (the newest RGB-D frame with a pose waits there).
		if (coarse && cfg.coarse.rgb_texture) {
			Pose world_from_rgb;
			bool posed = false;
			if (cfg.coarse_poses == PoseSource::GroundTruth) {
				posed = has_truth;
				world_from_rgb = truth;
			} else {
				posed = out->has_pose && out->state != TrackingState::Lost;
				world_from_rgb = out->world_from_camera;
			}
			if (posed) {
				world_from_rgb = compose(inverse(cfg.world_from_room), world_from_rgb); // into the room's frame
				const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
				pending_rgb = PendingRgb{ p_frame, world_from_rgb };
			}
		}
		// Read here, on the only thread that writes the volume: stats() never waits for a fusing.
		const TsdfStats volume_stats = slam ? slam->volume().stats() : TsdfStats();
		{
			const std::lock_guard<std::mutex> lock(stats_mutex);
			counters.tsdf = volume_stats;
			counters.rgbd_processed++;
			counters.good += out->state == TrackingState::Good ? 1 : 0;
			counters.poor += out->state == TrackingState::Poor ? 1 : 0;
			counters.lost += out->state == TrackingState::Lost ? 1 : 0;
		}
		bool remesh = false;
		{
			const std::lock_guard<std::mutex> lock(publish_mutex);
			last_tracked = out;
			if (fused && ++fused_since_mesh >= cfg.mesh_interval_frames) {
				remesh_due = true;
			}
			// While the mesh worker has not taken the last input, the changes wait in the volume.
			if (remesh_due && !(running && mesh_inputs.pending())) {
				remesh_due = false;
				fused_since_mesh = 0;
				remesh = true;
			}
		}
		if (remesh) {
			send_mesh_input();
		}
		if (fused) {
			wake_probes();
		}
	} catch (const std::exception &e) {
		record_error("SLAM", e.what());
	}
}

bool LiveRoom::fisheye_pose(double p_fisheye_timestamp_s, Pose *r_world_from_fisheye, std::string *r_error) const {
	if (cfg.coarse_poses == PoseSource::GroundTruth) {
		return fisheye_pose_at(cfg.ground_truth, cfg.rig, p_fisheye_timestamp_s, r_world_from_fisheye, r_error);
	}
	const std::lock_guard<std::mutex> lock(pose_mutex);
	if (tracked.is_empty()) {
		*r_error = "no tracked RGB-D pose yet";
		return false;
	}
	return fisheye_pose_at(tracked, cfg.rig, p_fisheye_timestamp_s, r_world_from_fisheye, r_error, cfg.fisheye_extrapolation_s);
}

void LiveRoom::process_fisheye(const FisheyeFrame &p_frame, uint64_t p_sequence, bool p_wait_for_pose) {
	if (!coarse) {
		return;
	}
	// A frame a failing driver or a damaged file delivers is refused at the door, named.
	const std::string problem = check_fisheye_image(p_frame, cfg.rig.fisheye.width, cfg.rig.fisheye.height);
	if (!problem.empty()) {
		record_error("fisheye frame", problem + " (frame skipped)");
		return;
	}
	try {
		if (p_wait_for_pose && cfg.coarse_poses == PoseSource::Tracked) {
			// SLAM may not have reached this instant yet: wait for it while it still has frames
			// to process, at most fisheye_pose_wait_s. The coarse model then follows SLAM's lag
			// instead of starving; newer fisheye frames meanwhile replace older ones in the mailbox.
			const double t_rgbd = p_frame.timestamp_s + cfg.rig.fisheye_time_offset_s;
			const double deadline = now_s() + cfg.fisheye_pose_wait_s;
			std::unique_lock<std::mutex> lock(pose_mutex);
			while (!stopping && (tracked.is_empty() || tracked.get_end_s() < t_rgbd) && now_s() < deadline &&
					frames->rgbd_outstanding()) {
				pose_advanced.wait_for(lock, std::chrono::milliseconds(10));
			}
		}
		Pose pose;
		std::string error;
		if (!fisheye_pose(p_frame.timestamp_s, &pose, &error)) {
			// Never integrated at a guess; the next frame may have a pose.
			const std::lock_guard<std::mutex> lock(stats_mutex);
			counters.fisheye_without_pose++;
			counters.fisheye_pose_problem = error;
			return;
		}
		pose = compose(inverse(cfg.world_from_room), pose); // into the room's frame
		FisheyeFrame frame = p_frame;
		LinearFrame linear = linearizer.linearise(p_frame.image, exposure_ratio(cfg.photometry.fisheye, p_frame.capture.exposure_us, p_frame.capture.gain));
		frame.image = linear.radiance;
		frame.saturated = linear.saturated;
		frame.hdr = frame.image.type() == CV_32FC3;
		auto snapshot = std::make_shared<CoarseSnapshot>();
		std::optional<PendingRgb> rgb;
		{
			const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
			rgb.swap(pending_rgb);
		}
		const std::lock_guard<std::mutex> coarse_lock(coarse_mutex);
		if (rgb) {
			coarse->add_rgb_frame(rgb->frame, cfg.rig.rgb, rgb->world_from_rgb, rgb_lut_active ? &rgb_lut : nullptr);
		}
		snapshot->last = coarse->add_fisheye_frame(frame, pose);
		snapshot->fisheye_sequence = p_sequence;
		take_coarse_state(snapshot.get());
		snapshot->timings = coarse->last_timings();
		{
			const std::lock_guard<std::mutex> lock(publish_mutex);
			last_coarse = snapshot;
		}
		{
			const std::lock_guard<std::mutex> lock(stats_mutex);
			counters.fisheye_integrated++;
		}
		wake_probes();
	} catch (const std::exception &e) {
		record_error("coarse model", e.what());
	}
}

// ---------------------------------------------------------------- the room: replaced, and found from the sweep

// The coarse pipeline's state as a snapshot holds it: the frame count, the completed atlas (a
// copy the pipeline will never write: probes read it while the next frame goes in), the observed
// mask the dense pass needs, and the lighting changes so far.
void LiveRoom::take_coarse_state(CoarseSnapshot *r_snapshot) const {
	r_snapshot->frames = coarse->frame_count();
	r_snapshot->atlas = coarse->completed_color().clone();
	if (cfg.coarse_shell_first) {
		r_snapshot->observed = observed_mask(coarse->texture());
	}
	r_snapshot->cumulative = coarse->cumulative_lighting();
}

std::string LiveRoom::set_room(bool p_has_room, const Floorplan &p_floorplan, const Pose &p_world_from_room, double p_texel_size_m, double p_carry_m,
		double *r_carried) {
	if (r_carried != nullptr) {
		*r_carried = 0.0;
	}
	if (!is_finite(p_world_from_room)) {
		return "the room's pose is not finite";
	}
	const std::unique_lock<std::shared_mutex> exclusive(lifecycle);
	if (!configured) {
		return "the engine is not configured: " + config_error;
	}
	const bool was_running = running;
	stop_locked();
	// The workers run again whatever happens below (an exception included).
	struct Restart {
		LiveRoom *engine;
		bool run;
		~Restart() {
			if (run) {
				engine->start_locked();
			}
		}
	} restart{ this, was_running };
	// The old room, kept to carry its texture over (and to go back to on failure).
	const LiveRoomConfig old_cfg = cfg;
	std::unique_ptr<CoarsePipeline> old_coarse = std::move(coarse);
	std::unique_ptr<RoomMesh> old_own = std::move(own_room);
	std::unique_ptr<CoarseCubemapRenderer> old_renderer = std::move(renderer);
	auto put_back = [&] {
		cfg = old_cfg;
		coarse = std::move(old_coarse);
		own_room = std::move(old_own);
		room_builds++;
		renderer = std::move(old_renderer);
		const std::lock_guard<std::mutex> lock(placer_mutex);
		placer.clear_coarse();
		if (room_mesh() != nullptr) {
			placer.set_coarse(*room_mesh(), cfg.world_from_room);
		}
	};
	cfg.has_room = p_has_room;
	cfg.floorplan = p_floorplan;
	cfg.world_from_room = p_world_from_room;
	if (p_texel_size_m > 0.0) {
		cfg.coarse.texel_size_m = p_texel_size_m;
	}
	try {
		const std::string error = build_room_locked();
		if (!error.empty()) {
			put_back();
			return error;
		}
		std::shared_ptr<CoarseSnapshot> snapshot;
		if (coarse && old_coarse && old_coarse->frame_count() > 0) {
			// The new room's frame from the old one's, through the world.
			const Pose new_from_old = compose(inverse(cfg.world_from_room), old_cfg.world_from_room);
			const double carried = coarse->carry_texture(*old_coarse, new_from_old, p_carry_m);
			if (r_carried != nullptr) {
				*r_carried = carried;
			}
			if (carried > 0.0) {
				std::shared_ptr<const CoarseSnapshot> before;
				{
					const std::lock_guard<std::mutex> lock(publish_mutex);
					before = last_coarse;
				}
				snapshot = std::make_shared<CoarseSnapshot>();
				snapshot->fisheye_sequence = before ? before->fisheye_sequence : 0;
				take_coarse_state(snapshot.get());
			}
		}
		{
			const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
			pending_rgb.reset(); // posed in the old room's frame
		}
		{
			const std::lock_guard<std::mutex> lock(publish_mutex);
			last_coarse = snapshot;
		}
	} catch (const std::exception &e) {
		put_back();
		return std::string("replacing the room failed: ") + e.what();
	}
	// A pending configuration (a node's edit not applied yet) gets the same room.
	{
		const std::lock_guard<std::mutex> lock(pending_mutex);
		if (has_pending) {
			pending.has_room = cfg.has_room;
			pending.floorplan = cfg.floorplan;
			pending.world_from_room = cfg.world_from_room;
			pending.coarse.texel_size_m = cfg.coarse.texel_size_m;
		}
	}
	const std::lock_guard<std::mutex> lock(probe_mutex);
	for (auto &[id, probe] : probes) {
		probe->dirty = true;
	}
	inputs_changed = true;
	input_generation++;
	probes_dirty.notify_all();
	return "";
}

void LiveRoom::keep_room_view(const FisheyeFrame &p_frame) {
	if (p_frame.image.empty() || cfg.find_room_views == 0) {
		return;
	}
	const std::lock_guard<std::mutex> lock(room_mutex);
	if (!room_views.empty() && p_frame.timestamp_s - room_views.back().timestamp_s < room_view_spacing_s) {
		return;
	}
	FisheyeFrame kept = p_frame;
	kept.image = p_frame.image.clone(); // a driver may reuse its buffer
	kept.saturated.release();
	room_views.push_back(std::move(kept));
	if (room_views.size() >= 2 * cfg.find_room_views) {
		// Every other one goes: the views stay spread over the whole sweep.
		std::vector<FisheyeFrame> thinned;
		for (size_t i = 0; i < room_views.size(); i += 2) {
			thinned.push_back(std::move(room_views[i]));
		}
		room_views = std::move(thinned);
		room_view_spacing_s *= 2.0;
	}
}

std::shared_ptr<const FoundRoom> LiveRoom::found_room() const {
	const std::lock_guard<std::mutex> lock(room_mutex);
	return last_found;
}

std::shared_ptr<const FoundRoom> LiveRoom::find_room_now(const std::vector<FisheyeFrame> *p_views) {
	const std::shared_lock<std::shared_mutex> shared(lifecycle); // no configure meanwhile
	try {
		return find_room_locked(p_views);
	} catch (const std::exception &e) {
		record_error("room estimation", e.what());
		auto failed = std::make_shared<FoundRoom>();
		failed->result.estimate.message = std::string("the room's estimation failed: ") + e.what();
		const std::lock_guard<std::mutex> lock(room_mutex);
		failed->version = last_found ? last_found->version + 1 : 1;
		last_found = failed;
		return failed;
	}
}

// The room worker calls this without the lifecycle lock: stop_locked joins it before the
// configuration changes.
std::shared_ptr<const FoundRoom> LiveRoom::find_room_locked(const std::vector<FisheyeFrame> *p_views) {
	const double start = now_s();
	auto found = std::make_shared<FoundRoom>();
	if (!running) {
		update_dense_mesh();
	}
	const std::shared_ptr<const DenseMeshSnapshot> mesh = dense_mesh();
	SweepObservations observed;
	if (mesh != nullptr && mesh->mesh != nullptr) {
		observed.samples = surface_samples(*mesh->mesh);
	}
	const Trajectory path = trajectory();
	for (const TimedPose &pose : path.get_samples()) {
		observed.camera_positions.push_back(pose.world_from_camera.translation);
	}
	if (!path.get_samples().empty()) {
		observed.has_first_camera = true;
		observed.model_from_first_rgb = path.get_samples().front().world_from_camera;
		observed.up_hint = sweep_up_hint(observed.model_from_first_rgb, cfg.rig.has_fisheye(), cfg.rig.rgb_from_fisheye);
	}
	std::vector<FisheyeFrame> kept;
	if (p_views == nullptr) {
		const std::lock_guard<std::mutex> lock(room_mutex);
		kept = room_views;
		p_views = &kept;
	}
	observed.has_fisheye = cfg.rig.has_fisheye();
	observed.fisheye = cfg.rig.fisheye;
	for (const FisheyeFrame &frame : *p_views) {
		Pose world_from_fisheye;
		std::string error;
		if (fisheye_pose(frame.timestamp_s, &world_from_fisheye, &error)) {
			observed.fisheye_views.push_back({ frame.image, world_from_fisheye });
		}
	}
	found->fisheye_views = observed.fisheye_views.size();
	if (!slam) {
		found->result.estimate.message = "no dense model: finding the room needs dense SLAM";
	} else {
		found->result = find_room_from_sweep(observed, cfg.room_estimation);
	}
	found->samples = std::move(observed.samples);
	found->fused_frames = slam ? slam->integrated_count() : 0;
	found->seconds = now_s() - start;
	const std::lock_guard<std::mutex> lock(room_mutex);
	found->version = last_found ? last_found->version + 1 : 1;
	found_mesh_version = mesh ? mesh->version : 0;
	last_found = found;
	return found;
}

void LiveRoom::room_worker() {
	while (!stopping) {
		{
			std::unique_lock<std::mutex> lock(room_mutex);
			room_wake.wait_for(lock, std::chrono::duration<double>(std::max(cfg.find_room_interval_s, 0.1)), [this] { return bool(stopping); });
			if (stopping) {
				return;
			}
		}
		const std::shared_ptr<const DenseMeshSnapshot> mesh = dense_mesh();
		uint64_t seen = 0;
		{
			const std::lock_guard<std::mutex> lock(room_mutex);
			seen = found_mesh_version;
		}
		if (mesh == nullptr || mesh->version == seen) {
			continue; // nothing new to look at
		}
		try {
			find_room_locked(nullptr);
		} catch (const std::exception &e) {
			record_error("room estimation", e.what());
		}
	}
}

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

Cubemap LiveRoom::render_map(const glm::dvec3 &p_position, int p_size, const CoarseSnapshot *p_coarse, bool p_with_dense, DenseRenderStats *r_dense,
		double *r_coarse_ms, double *r_dense_ms, DenseFaceCache *io_faces) {
	double start = now_s();
	Cubemap map;
	LightingChange cumulative;
	cumulative.valid = true;
	std::array<cv::Mat, 6> observed; // which texels the coarse model's fisheye observations show
	if (renderer && p_coarse != nullptr && !p_coarse->atlas.empty()) {
		const Pose room_from_world = inverse(cfg.world_from_room);
		const glm::dvec3 in_room = transform_point(room_from_world, p_position);
		map = renderer->render(p_coarse->atlas, in_room, p_size, room_from_world.rotation);
		if (p_with_dense && slam && cfg.coarse_shell_first && !p_coarse->observed.empty()) {
			observed = renderer->render_channel(p_coarse->observed, in_room, p_size, room_from_world.rotation);
		}
		cumulative = p_coarse->cumulative;
	} else {
		// No observation yet (or no room): black, with the dense model over it, and no distances
		// but the dense model's.
		map = make_cubemap(p_size);
		for (cv::Mat &face : map.distance_m) {
			face = cv::Mat(p_size, p_size, CV_32FC1, cv::Scalar(0.0f));
		}
	}
	*r_coarse_ms = ms_since(start);
	start = now_s();
	if (p_with_dense && slam) {
		DenseRenderOptions options;
		options.scale = cfg.dense_render_scale;
		options.far_m = cfg.dense_render_far_m;
		options.coarse_observed = observed[0].empty() ? nullptr : &observed;
		options.lut = rgb_lut_active ? &rgb_lut : nullptr;
		options.faces_per_render = cfg.dense_faces_per_render;
		const auto reading = slam->read_lock(); // no frame half-fused
		*r_dense = dense_lighting.render_over(slam->volume(), slam->integrated_count(), cumulative, p_position, options, &map, io_faces);
	}
	*r_dense_ms = ms_since(start);
	r_dense->milliseconds = *r_dense_ms;
	return map;
}

std::shared_ptr<const ProbeMap> LiveRoom::render_one(int p_probe, const glm::dvec3 &p_position, int p_size, uint64_t p_generation) {
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
		map->cubemap = render_map(p_position, p_size, snapshot.get(), true, &map->dense, &map->coarse_ms, &map->dense_ms, probe ? &probe->dense_faces : nullptr);
		double t = now_s();
		if (objects && objects->object_count() > 0) {
			// Lit by the probe's previous map when it has one (it holds the objects too), else by
			// this map's room alone.
			const bool reuse = previous && previous->cubemap.size == p_size;
			const ShCoefficients light = reuse ? previous->sh : project_sh(map->cubemap);
			map->objects = objects->draw(p_position, light, reuse ? &previous->cubemap : nullptr, &map->cubemap);
		}
		map->sh = project_sh(map->cubemap);
		map->sh_ms = ms_since(t) - map->objects.milliseconds;
		t = now_s();
		build_gpu_faces(previous.get(), map.get());
		map->mips_ms = ms_since(t);
		map->total_ms = ms_since(start);
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

// The GGX chain and the faces as Godot takes them. Only what the map changed against the probe's
// previous one is done again: the chain's texels that read a changed face, and the faces whose
// chain or distances changed (dense faces take turns, and the coarse model changes with fisheye
// frames only, so most maps change one or two faces).
void LiveRoom::build_gpu_faces(const ProbeMap *p_previous, ProbeMap *io_map) const {
	const int size = io_map->cubemap.size;
	const std::shared_ptr<const GgxFilter> filter = shared_ggx_filter(size, cfg.wait_for_ggx_filter);
	const bool same_kind = p_previous != nullptr && p_previous->cubemap.size == size && p_previous->ggx_mips == (filter != nullptr);
	const uint8_t source_changed = same_kind ? cubemap_changed_faces(p_previous->cubemap, io_map->cubemap) : uint8_t(0x3F);
	uint8_t chain_changed = source_changed;
	std::vector<Cubemap> chain;
	if (filter) {
		chain = filter->apply(io_map->cubemap, same_kind ? p_previous->ggx_chain : std::vector<Cubemap>{}, source_changed, &chain_changed);
	} else {
		chain = { io_map->cubemap };
	}
	io_map->ggx_mips = filter != nullptr;
	tbb::parallel_for(0, 6, [&](int p_face) {
		const size_t f = size_t(p_face);
		const cv::Mat &distance = io_map->cubemap.distance_m[f];
		const bool same = same_kind && !(chain_changed & (1u << p_face)) && p_previous->gpu_faces[f] && same_pixels(distance, p_previous->cubemap.distance_m[f]);
		io_map->gpu_faces[f] = same ? p_previous->gpu_faces[f] : std::make_shared<const std::vector<uint16_t>>(gpu_face(chain, distance, p_face));
	});
	if (filter) {
		io_map->ggx_chain = std::move(chain);
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
	const CoarseSnapshot *source = snapshot.get();
	CoarseSnapshot raw;
	if (!p_completed && coarse && !running) {
		// The observations alone (no inpainting), straight from the pipeline: nothing writes it now.
		raw.atlas = coarse->texture().color;
		raw.observed = cfg.coarse_shell_first ? observed_mask(coarse->texture()) : cv::Mat();
		raw.cumulative = coarse->cumulative_lighting();
		source = &raw;
	}
	DenseRenderStats dense;
	double coarse_ms = 0.0, dense_ms = 0.0;
	Cubemap map = render_map(p_position, p_size, source, p_with_dense, &dense, &coarse_ms, &dense_ms);
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
	const std::lock_guard<std::mutex> lock(pose_mutex);
	return tracked;
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
	{
		const std::lock_guard<std::mutex> coarse_lock(coarse_mutex);
		coarse->finish_inpainting();
		const std::lock_guard<std::mutex> lock(publish_mutex);
		if (last_coarse) {
			auto snapshot = std::make_shared<CoarseSnapshot>(*last_coarse);
			snapshot->atlas = coarse->completed_color().clone();
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
		s.rgbd_latency = summarise_latency(rgbd_latencies_ms);
		s.fisheye_latency = summarise_latency(fisheye_latencies_ms);
	}
	s.running = running;
	s.rgbd_dropped = frames->rgbd.dropped_count();
	s.fisheye_dropped = frames->fisheye.dropped_count();
	if (slam) {
		s.dense_frames = slam->frame_count();
		s.dense_fused = slam->integrated_count();
		s.relocalisation_attempts = slam->relocalisation_attempts();
		s.relocalisations = slam->relocalisation_count();
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
