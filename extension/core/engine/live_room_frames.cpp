#include "live_room_internal.h"

#include <rig/fisheye_pose.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace roomprobe {

using namespace live_room_detail;

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
	if (configured && cfg.has_rig && !cfg.rig.has_fisheye()) {
		record_error("fisheye frame", "the rig has no fisheye (an RGB-D camera alone): frame skipped");
		return;
	}
	if (configured && cfg.has_rig && cfg.find_room) {
		room_finder.keep_view(p_frame, cfg.find_room_views);
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
		if (p_frame.rgb.type() == CV_8UC3) {
			make_buffer_image(cfg.display_buffers, p_frame.rgb.rows, p_frame.rgb.cols, CV_8UC4, &out->rgba);
			cv::cvtColor(p_frame.rgb, out->rgba.mat, cv::COLOR_RGB2RGBA);
			CV_Assert(out->rgba.mat.data == out->rgba.bytes->data()); // written in place
		}
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
				tracked.append(p_frame.timestamp_s, slam->pose());
			}
			fused = result.integrated;
			if (fused) {
				// These colours are of the coarse model's lighting now (§4.6): the probes give each
				// block the changes since its last fused frame (DenseLighting).
				const std::shared_ptr<const CoarseSnapshot> lighting = coarse_snapshot();
				dense_lighting.record(slam->volume().frame_count(), lighting ? lighting->cumulative : LightingChange());
			}
		} else if (has_truth) {
			// No SLAM: the AR view still follows the recording's true poses.
			out->has_pose = true;
			out->world_from_camera = truth;
			out->state = TrackingState::Good;
		}
		// The coarse model takes the texels its fisheye never saw from this frame, on its own
		// thread at its next fisheye frame (the newest RGB-D frame with a pose waits there);
		// without a fisheye the frame is its view.
		if (coarse && (cfg.coarse.rgb_texture || coarse->rgb_only())) {
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
				offer_rgb(p_frame, compose(inverse(cfg.world_from_room), world_from_rgb)); // into the room's frame
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

void LiveRoom::offer_rgb(const RgbdFrame &p_frame, const Pose &p_world_from_rgb) {
	if (!coarse->rgb_only()) {
		const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
		pending_rgb = PendingRgb{ p_frame, p_world_from_rgb };
		return;
	}
	if (p_frame.timestamp_s < next_rgb_view_s) {
		return;
	}
	next_rgb_view_s = p_frame.timestamp_s + cfg.rgb_view_interval_s;
	if (!running) {
		process_rgb_view(PendingRgb{ p_frame, p_world_from_rgb }); // step mode: now, in order
		return;
	}
	{
		const std::lock_guard<std::mutex> lock(pending_rgb_mutex);
		pending_rgb = PendingRgb{ p_frame, p_world_from_rgb };
	}
	pending_rgb_ready.notify_one();
}

std::optional<LiveRoom::PendingRgb> LiveRoom::take_rgb_view(std::chrono::milliseconds p_wait) {
	std::unique_lock<std::mutex> lock(pending_rgb_mutex);
	pending_rgb_ready.wait_for(lock, p_wait, [this] { return stopping || pending_rgb.has_value(); });
	std::optional<PendingRgb> view;
	view.swap(pending_rgb);
	return view;
}

void LiveRoom::process_rgb_view(const PendingRgb &p_view) {
	try {
		auto snapshot = std::make_shared<CoarseSnapshot>();
		{
			const std::lock_guard<std::mutex> coarse_lock(coarse_mutex);
			snapshot->last = coarse->add_rgb_view(p_view.frame, cfg.rig.rgb, p_view.world_from_rgb, rgb_lut_active ? &rgb_lut : nullptr);
			take_coarse_state(snapshot.get());
			snapshot->timings = coarse->last_timings();
		}
		publish_coarse(snapshot, &LiveRoomStats::rgb_views_integrated);
	} catch (const std::exception &e) {
		record_error("coarse (RGB view)", e.what());
	}
}

void LiveRoom::publish_coarse(std::shared_ptr<const CoarseSnapshot> p_snapshot, uint64_t LiveRoomStats::*p_counter) {
	{
		const std::lock_guard<std::mutex> lock(publish_mutex);
		last_coarse = std::move(p_snapshot);
	}
	{
		const std::lock_guard<std::mutex> lock(stats_mutex);
		(counters.*p_counter)++;
	}
	wake_probes();
}

bool LiveRoom::fisheye_pose(double p_fisheye_timestamp_s, Pose *r_world_from_fisheye, std::string *r_error) const {
	if (cfg.coarse_poses == PoseSource::GroundTruth) {
		return fisheye_pose_at(cfg.ground_truth, cfg.rig, p_fisheye_timestamp_s, r_world_from_fisheye, r_error);
	}
	return tracked.fisheye_pose(cfg.rig, p_fisheye_timestamp_s, cfg.fisheye_extrapolation_s, r_world_from_fisheye, r_error);
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
			tracked.wait_until_reaches(p_frame.timestamp_s + cfg.rig.fisheye_time_offset_s, cfg.fisheye_pose_wait_s,
					[this] { return !stopping && frames->rgbd_outstanding(); });
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
		publish_coarse(snapshot, &LiveRoomStats::fisheye_integrated);
	} catch (const std::exception &e) {
		record_error("coarse model", e.what());
	}
}

// ---------------------------------------------------------------- the room: replaced, and found from the sweep

// The coarse pipeline's state as a snapshot holds it: the frame count, the completed atlas (a
// copy the pipeline will never write: probes read it while the next frame goes in), the observed
// mask the dense pass needs, and the lighting changes so far.
void CoarseSnapshot::set_atlas(const cv::Mat &p_atlas, const PixelBufferFactory &p_buffers) {
	atlas = p_atlas;
	display = BufferImage();
	if (p_atlas.type() == CV_32FC3) {
		cv::Mat rgba;
		cv::cvtColor(p_atlas, rgba, cv::COLOR_RGB2RGBA);
		make_buffer_image(p_buffers, p_atlas.rows, p_atlas.cols, CV_16FC4, &display);
		rgba.convertTo(display.mat, CV_16F);
		CV_Assert(display.mat.data == display.bytes->data()); // written in place
	}
}

void LiveRoom::take_coarse_state(CoarseSnapshot *r_snapshot) const {
	r_snapshot->frames = coarse->frame_count();
	r_snapshot->set_atlas(coarse->completed_color().clone(), cfg.display_buffers);
	if (cfg.coarse_shell_first) {
		r_snapshot->observed = observed_mask(coarse->texture(), coarse->rgb_only());
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
	std::unique_ptr<ProbeRenderer> old_renderer = std::move(renderer);
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

std::shared_ptr<const FoundRoom> LiveRoom::found_room() const {
	return room_finder.found();
}

std::shared_ptr<const FoundRoom> LiveRoom::find_room_now(const std::vector<FisheyeFrame> *p_views) {
	const std::shared_lock<std::shared_mutex> shared(lifecycle); // no configure meanwhile
	try {
		return find_room_locked(p_views);
	} catch (const std::exception &e) {
		record_error("room estimation", e.what());
		return room_finder.publish_failure(std::string("the room's estimation failed: ") + e.what());
	}
}

// What the room finder estimates from: the dense surface, the camera path and the fisheye views
// at their poses. The room worker calls this without the lifecycle lock: stop_locked joins it
// before the configuration changes.
std::shared_ptr<const FoundRoom> LiveRoom::find_room_locked(const std::vector<FisheyeFrame> *p_views) {
	const auto start = std::chrono::steady_clock::now();
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
	const std::vector<FisheyeFrame> kept = p_views == nullptr ? room_finder.views() : std::vector<FisheyeFrame>();
	observed.has_fisheye = cfg.rig.has_fisheye();
	observed.fisheye = cfg.rig.fisheye;
	for (const FisheyeFrame &frame : p_views == nullptr ? kept : *p_views) {
		Pose world_from_fisheye;
		std::string error;
		if (fisheye_pose(frame.timestamp_s, &world_from_fisheye, &error)) {
			observed.fisheye_views.push_back({ frame.image, world_from_fisheye });
		}
	}
	return room_finder.estimate(std::move(observed), slam != nullptr, slam ? slam->integrated_count() : 0, mesh ? mesh->version : 0, cfg.room_estimation, start);
}

void LiveRoom::room_worker() {
	while (room_finder.wait(cfg.find_room_interval_s, stopping)) {
		const std::shared_ptr<const DenseMeshSnapshot> mesh = dense_mesh();
		if (mesh == nullptr || mesh->version == room_finder.estimated_mesh_version()) {
			continue; // nothing new to look at
		}
		try {
			find_room_locked(nullptr);
		} catch (const std::exception &e) {
			record_error("room estimation", e.what());
		}
	}
}

} // namespace roomprobe
