#pragma once
// LiveRoom: the one live system (paper §3.1, Figure 2), as InfiniTAM's main engine is: the Godot
// nodes, roomprobe_eval and roomprobe_bench all drive this object, so what is measured is what
// ships. It owns:
//   the rig (geometry and photometry) and the room (one coarse pipeline with its room mesh and atlas);
//   DenseSlam, the RGB-D pose history and the fisheye's pose at its own timestamp (§4.3);
//   the coarse pipeline (§4.3-§4.6) with its inpainting worker (§4.5);
//   the probes, each map rendered by envmap/probe_renderer.h's ProbeRenderer (§4.7: coarse render,
//     dense pass, virtual objects, SH, GGX chain, upload faces), which render_at shares;
//   the room finder stage (room_finder_stage.h), with its own lock;
//   placement rays (Embree) against the dense mesh and the room.
//
// Two ways to run the same code:
//   step mode (no start()): push_rgbd / push_fisheye process the frame before they return, and
//     render_probes() renders; deterministic, for tests, the evaluation and the step-paced node.
//   threaded (start() .. stop()): push_* only post the frame into a latest-value mailbox
//     (engine/mailbox.h) and return; a SLAM worker, a coarse worker and a probe worker take the
//     newest frame each (a slow stage drops frames and counts them), and readers take immutable
//     results: probe maps, the tracked frame, the dense mesh, the coarse atlas. A mesh worker
//     meshes the blocks the SLAM worker copies every mesh_interval_frames, then builds the
//     placement scene (TsdfBlockCopy: the volume fuses on meanwhile). Probes render
//     while the next frame is tracked; only fusing a frame into the TSDF excludes the dense pass
//     (DenseSlam::read_lock). stop() joins within about one stage.
// Workers never call Godot and never throw out: a stage's exception is counted and reported in
// stats().last_error, and the frame is skipped.
//
// Frames come in with timestamps on their own device clocks (RgbdFrame, FisheyeFrame); the
// fisheye's pose is the RGB-D trajectory at fisheye timestamp + Rig::fisheye_time_offset_s.

#include "dense_mesh_stage.h"
#include "mailbox.h"
#include "pose_history.h"
#include "room_finder_stage.h"

#include <envmap/dense_render.h>
#include <envmap/ggx_prefilter.h>
#include <envmap/probe_renderer.h>
#include <prt/virtual_objects.h>
#include <pipeline/coarse_pipeline.h>
#include <room/room_from_sweep.h>
#include <placement/surface_placement.h>
#include <rig/photometry.h>
#include <rig/rig.h>
#include <rig/trajectory.h>
#include <slam/dense_slam.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <thread>
#include <vector>

namespace roomprobe {

struct LiveRoomConfig {
	// Without a rig (has_rig false) the engine holds only the room: no frames are taken, and the
	// maps render whatever atlas set_atlas() put in (CoarseRoomModel's texture hook, the editor).
	bool has_rig = true;
	Rig rig;
	RigPhotometry photometry; // unknown: frames as recorded (rig/photometry.h)
	bool has_room = false; // false: no coarse model (maps then hold only the dense model)
	Floorplan floorplan; // metres, with the ceiling height
	// The room's frame in the world (the CoarseRoomModel node's transform, or the room found from
	// the sweep): the coarse model lives in the room's frame, the dense model and the probes in
	// the world's. A turned room is fine: its maps' faces stay the world's.
	Pose world_from_room;
	Pose initial_rgb_pose; // world_from_rgb at the first RGB-D frame (room.yaml's)
	std::vector<glm::dvec3> keep_points; // the TSDF evicts blocks far from these last (the probes)
	// Find the room from the sweep (issue #18; CoarseRoomModel's Automatic source): the engine
	// keeps fisheye frames spread over the sweep (at most 2 find_room_views - 1; thinned to
	// find_room_views when more would be kept), and its room worker
	// estimates the room from the dense model every find_room_interval_s while it runs (or at
	// find_room_now()). Needs dense SLAM.
	bool find_room = false;
	double find_room_interval_s = 2.0;
	size_t find_room_views = 24;
	RoomEstimationOptions room_estimation;
	bool dense = true; // run dense SLAM (§4.2) and draw the dense model into the maps
	// Where poses come from. Tracked: DenseSlam's trajectory (the live mode). GroundTruth: the
	// recording's true RGB-D trajectory (evaluation mode): the coarse model takes its fisheye poses
	// from it, and the dense model fuses each RGB-D frame at its true pose.
	PoseSource coarse_poses = PoseSource::Tracked;
	PoseSource dense_poses = PoseSource::Tracked;
	Trajectory ground_truth; // RGB-D clock; needed by either GroundTruth
	DenseSlamOptions slam;
	CoarsePipelineOptions coarse; // inpaint_async: the nodes turn it on (live), the evaluation off (deterministic)
	// A rig without a fisheye (an RGB-D camera alone, issue #43): the coarse model takes an RGB-D
	// frame with a pose as its view at most this often, seconds of the RGB-D clock (the synthetic
	// recordings' fisheye rate). Its views then cost the coarse worker what fisheye frames would.
	double rgb_view_interval_s = 1.0 / 12.0;
	// Re-mesh the dense model every this many fused frames (threaded: or later, when the mesh
	// worker is still busy with the last ones).
	int mesh_interval_frames = 15;
	// A fisheye frame may come a little after the newest tracked RGB-D frame: the tracked
	// trajectory is extrapolated this far (seconds). Ground truth is never extrapolated.
	double fisheye_extrapolation_s = 0.1;
	// Threaded: a fisheye frame newer than the tracked trajectory waits for SLAM to catch up
	// while SLAM still has frames to process, at most this long (seconds); then it is
	// extrapolated (fisheye_extrapolation_s) or skipped.
	double fisheye_pose_wait_s = 1.0;
	int render_threads = 1; // threaded: worker threads for probe rendering (cores left to Godot)
	int dense_render_scale = DenseRenderOptions().scale; // the dense pass at 1 / scale (dense_render.h)
	float dense_render_far_m = DenseRenderOptions().far_m; // the dense pass's reach from the probe (dense_render.h)
	// Where the dense model shows the room's shell and the fisheye observed it, the map keeps the
	// coarse model (DenseRenderOptions::coarse_observed). False: the paper's dense-over-all.
	bool coarse_shell_first = true;
	// A probe's map raycasts this many of its six dense faces (round robin) and reuses the others
	// from its earlier maps while it stays put (dense_render.h DenseFaceCache): with 2, a face's
	// dense layer is at most two maps older than the map. 6: every face every map. render_at()
	// (the evaluation) always raycasts all six.
	int dense_faces_per_render = 2;
	// The maps' mips are GGX-prefiltered (envmap/ggx_prefilter.h) once the filter for their size is
	// built: at once up to 64^2 faces, otherwise in the background (about 3 s at 256^2, once per
	// process), box-filtered meanwhile. True: wait for it instead (the benchmark, the evaluation).
	bool wait_for_ggx_filter = false;
	// Where the kernels that have a GPU twin run (issue #40; so far the coarse render's gather, the
	// GGX prefilter, SH, tracking's depth pyramid and normal equations, the TSDF's voxel updates
	// and its raycasts):
	// Cpu; Vulkan (any Vulkan device, Mesa's lavapipe included); Auto (Vulkan where a device that
	// is not a CPU exists). No device: the CPU, and stats().compute says why.
	ComputeBackend compute_backend = ComputeBackend::Cpu;
	// Where the images for display are filled on the workers (ProbeMap::gpu_faces,
	// TrackedFrame::rgba, CoarseSnapshot::display): a host engine's own buffers, which it then
	// takes without a copy. Empty: plain vectors.
	PixelBufferFactory display_buffers;
};

// One RGB-D frame as the engine saw it: the image the AR view shows behind the virtual objects
// together with the very pose it was taken at, so the two can never slip apart.
struct TrackedFrame {
	uint64_t sequence = 0; // 1, 2, ... in push order
	double timestamp_s = 0.0; // RGB-D clock
	// CV_8UC4 R, G, B, 255 of the pushed image (not undistorted), for showing: made on the worker
	// in the layout GPUs sample as it is, so a display uploads it without converting.
	BufferImage rgba;
	Pose world_from_camera; // the RGB camera's pose (held while Lost)
	bool has_pose = false; // false: no pose yet (not configured, or ground truth missing there)
	TrackingState state = TrackingState::Lost;
	std::string reason;
	bool integrated = false;
	double inlier_fraction = 0.0, rmse_m = 0.0;
	double constraint = 0.0; // the weakest direction's share of the information (slam_types.h)
	bool colour_used = false, relocalised = false;
	DenseSlamTimings timings;
};

struct CoarseSnapshot {
	uint64_t frames = 0; // fisheye frames integrated
	uint64_t fisheye_sequence = 0; // the last one
	cv::Mat atlas; // completed colour (CV_32FC3), never written after publishing
	// The atlas as RGBA half floats (CV_16FC4), for showing the room: made on the worker that
	// publishes, in the layout GPUs sample as it is (set_atlas).
	BufferImage display;
	// CV_32FC1, the atlas's size: 1 where the fisheye observed the texel (quality > 0), else 0; the
	// dense pass leaves those texels of the room's shell to the coarse model (dense_render.h).
	// Empty: none (set_atlas).
	cv::Mat observed;
	LightingChange cumulative; // the coarse model's lighting changes so far (§4.6)
	CoarseFrameStats last; // of the last frame
	CoarsePipelineTimings timings; // of the last frame

	// atlas = p_atlas (shared, not copied), and its display form in p_buffers' buffer.
	void set_atlas(const cv::Mat &p_atlas, const PixelBufferFactory &p_buffers);
};

// Nearest-rank percentiles of a latency series, milliseconds.
struct LatencySummary {
	size_t count = 0;
	double p50_ms = 0.0, p95_ms = 0.0, max_ms = 0.0;
};
LatencySummary summarise_latency(std::vector<double> p_values_ms);

struct LiveRoomStats {
	bool running = false;
	uint64_t rgbd_pushed = 0, rgbd_processed = 0, rgbd_dropped = 0;
	uint64_t fisheye_pushed = 0, fisheye_integrated = 0, fisheye_dropped = 0;
	uint64_t rgb_views_integrated = 0; // without a fisheye: RGB-D frames the coarse model took as views
	uint64_t fisheye_without_pose = 0; // skipped: no pose at their timestamp (never integrated at a guess)
	uint64_t probe_renders = 0;
	uint64_t good = 0, poor = 0, lost = 0;
	uint64_t stage_errors = 0;
	std::string last_error; // the last stage exception or frame problem, naming the stage
	std::string fisheye_pose_problem; // why the last skipped fisheye frame had no pose
	// From a frame's push to the first probe map that includes it.
	LatencySummary rgbd_latency, fisheye_latency;
	size_t dense_frames = 0, dense_fused = 0;
	size_t relocalisation_attempts = 0, relocalisations = 0; // lost frames searched, and found again
	size_t keyframes = 0, keyframe_relocalisations = 0; // dense SLAM's keyframes, and the relocalisations that came from one
	TsdfStats tsdf;
	// Where the GPU-capable kernels run: "CPU", "Vulkan: <device>", or "CPU (<backend>: <why not>)";
	// "; tracking on the CPU (<why>)", "; integration on the CPU (<why>)" or "; raycasts on the
	// CPU (<why>)" is added when dense SLAM's kernels failed while the others did not.
	std::string compute = "CPU";
	bool compute_on_device = false; // every kernel with a GPU twin runs on the device (compute says where not)
};

class LiveRoom {
public:
	LiveRoom();
	~LiveRoom(); // stops the workers
	LiveRoom(const LiveRoom &) = delete;
	LiveRoom &operator=(const LiveRoom &) = delete;

	// Builds the models from p_config (stopping the workers first; they stay stopped). The error
	// (empty on success) names the problem. Probes are kept.
	std::string configure(const LiveRoomConfig &p_config);
	// configure() with the current configuration changed by p_edit, restarting the workers if
	// they ran. The nodes use it when a property changes.
	std::string reconfigure(const std::function<void(LiveRoomConfig &)> &p_edit);
	bool is_configured() const { return configured; }
	// Whether the configured engine runs dense SLAM (a DenseSLAM node turned it on).
	bool has_dense() const { return slam != nullptr; }
	LiveRoomConfig config() const;
	// The configured RGB camera's intrinsics (cheap, unlike a copy of config()).
	PinholeParams rgb_camera() const { return cfg.rig.rgb; }
	std::string configuration_error() const;

	// Threads (see above). start() is a no-op when running; false when not configured.
	bool start();
	void stop();
	bool is_running() const { return running; }

	// Configuration in pieces, for the nodes (each owns part of it): p_edit changes the pending
	// configuration, which apply_config() configures (restarting the workers if they ran).
	void edit_config(const std::function<void(LiveRoomConfig &)> &p_edit);
	bool config_pending() const;
	std::string apply_config();

	// Replaces the room (floorplan, pose and texel size; p_texel_size_m 0: kept) and keeps
	// everything else: the dense model, the tracking, the probes. Only the coarse model is built
	// again; its texture carries over where the new room's surface lies within p_carry_m of the
	// old one's (the same kind of surface facing the same way), the rest is observed anew. The
	// error (empty on success) names the problem; the old room stays then. r_carried: the share
	// of the new surface that takes an observation over. The workers stop for it (joining the
	// room worker waits for an estimate under way).
	std::string set_room(bool p_has_room, const Floorplan &p_floorplan, const Pose &p_world_from_room, double p_texel_size_m = 0.0,
			double p_carry_m = 0.05, double *r_carried = nullptr);

	// The room from the sweep (LiveRoomConfig::find_room). found_room(): the newest estimate (null
	// before the first). find_room_now(): estimates now on the calling thread from the dense model
	// as it is (re-meshed first in step mode) and p_views (null: the fisheye frames the engine kept),
	// publishes and returns it. Needs dense SLAM; never throws.
	std::shared_ptr<const FoundRoom> found_room() const;
	std::shared_ptr<const FoundRoom> find_room_now(const std::vector<FisheyeFrame> *p_views = nullptr);

	// Puts a whole atlas in as the coarse texture (CV_32FC3 linear R, G, B, the room's atlas
	// size): the maps show it until the next fisheye frame. False when the size is wrong.
	bool set_atlas(const cv::Mat &p_atlas);

	// Frames in. Step mode: processed before returning. Threaded: posted. Ignored without a rig.
	void push_rgbd(RgbdFrame p_frame);
	void push_fisheye(FisheyeFrame p_frame);

	// Probes (ids from add_probe). p_size: cubemap face size in texels (1..4096).
	int add_probe(const glm::dvec3 &p_position, int p_size);
	void set_probe(int p_probe, const glm::dvec3 &p_position, int p_size);
	// The virtual objects drawn into this probe's maps (prt/virtual_objects.h; null: none).
	// The probe's own object must not be among them. A new scene marks the probe for a new map.
	void set_probe_objects(int p_probe, std::shared_ptr<const VirtualScene> p_objects);
	void remove_probe(int p_probe);
	// Every probe's position, world metres, in id order.
	std::vector<glm::dvec3> probe_positions() const;
	// Step mode, or any time: renders every probe (or one) now on the calling thread.
	void render_probes();
	bool render_probe(int p_probe);
	// Whether the probe's newest map is of its current position, size and objects and of the
	// newest inputs (nothing to render; the editor's idle test).
	bool probe_is_current(int p_probe) const;
	// The newest map of a probe (null before the first).
	std::shared_ptr<const ProbeMap> probe_map(int p_probe) const;
	// A one-off map at any position and size (the evaluation): the completed or raw coarse
	// texture, with or without the dense model. Invalid without a room or a dense model to draw.
	Cubemap render_at(const glm::dvec3 &p_position, int p_size, bool p_completed = true, bool p_with_dense = true, DenseRenderStats *r_dense = nullptr);

	std::shared_ptr<const TrackedFrame> tracked_frame() const;
	std::shared_ptr<const CoarseSnapshot> coarse_snapshot() const;
	std::shared_ptr<const DenseMeshSnapshot> dense_mesh() const;
	// Re-meshes the dense model now and publishes it (step mode; threaded, the SLAM worker copies
	// the changed blocks every mesh_interval_frames and the mesh worker meshes them).
	void update_dense_mesh();
	// The tracked RGB-D trajectory (the ground truth's in GroundTruth mode).
	Trajectory trajectory() const;
	// The fisheye's pose at its timestamp, from the pose history as the coarse model takes it.
	bool fisheye_pose(double p_fisheye_timestamp_s, Pose *r_world_from_fisheye, std::string *r_error) const;
	// The room's mesh (null without a room). Valid until the next configure.
	const RoomMesh *room_mesh() const;
	// The renderer every map comes from (null until configured). Valid until the next configure
	// or set_room; the evaluation renders its direction masks through its coarse renderer.
	const ProbeRenderer *probe_renderer() const { return renderer.get(); }
	// Counts the rooms made (configure, set_room, a room found): a new number is a new room, which
	// a probe updated once per room (RoomProbe's Once) renders again.
	uint64_t room_version() const { return room_builds.load(); }
	// How far a world point lies outside the room's prism, metres (0 inside, and without a room).
	double distance_outside_room_m(const glm::dvec3 &p_world) const;

	PlacementHit place_ray(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_max_distance_m = 100.0) const;

	// Step mode: waits for the inpainting worker's newest completion (end of a recording).
	// Threaded: first waits until the workers have finished every posted frame, then until every
	// probe has a map of the final model (all six dense faces raycast again).
	void finish();
	LiveRoomStats stats() const;
	// The SLAM and coarse models themselves, for the evaluation's figures. Step mode only (no
	// worker may be writing): null while running or without them.
	const DenseSlam *slam_model() const;
	const CoarsePipeline *coarse_model() const;

private:
	struct Probe;
	struct Frames;

	std::string configure_locked(const LiveRoomConfig &p_config);
	bool start_locked();
	void stop_locked();
	void process_rgbd(const RgbdFrame &p_frame, uint64_t p_sequence);
	void process_fisheye(const FisheyeFrame &p_frame, uint64_t p_sequence, bool p_wait_for_pose);
	// p_generation: input_generation when the render was decided (its inputs are at least that new).
	std::shared_ptr<const ProbeMap> render_one(int p_probe, const glm::dvec3 &p_position, int p_size, uint64_t p_generation);
	void send_mesh_input();
	void mesh_and_publish(DenseMeshStage::Input &p_input);
	void slam_worker();
	void coarse_worker();
	void probe_worker();
	void room_worker();
	void mesh_worker();
	void place_on(const TriangleMesh &p_mesh);
	std::shared_ptr<const FoundRoom> find_room_locked(const std::vector<FisheyeFrame> *p_views);
	std::string build_room_locked(); // the coarse model, the probe renderer and placement from cfg
	// The models' parts of a map, for the renderer: a coarse snapshot's, and the dense model's
	// (none when p_with_dense is false or there is no dense model).
	static CoarseMapInput coarse_input(const CoarseSnapshot &p_snapshot);
	DenseMapInput dense_input(bool p_with_dense);
	void take_coarse_state(CoarseSnapshot *r_snapshot) const; // coarse must exist
	void record_error(const std::string &p_stage, const std::string &p_what);
	// Counts a pushed frame and keeps its push time for the latency figures.
	void note_arrival(uint64_t p_sequence, double p_arrival_s, uint64_t *io_pushed, std::vector<std::pair<uint64_t, double>> *io_arrivals);
	void note_latency(const ProbeMap &p_map);
	void wake_probes();

	// Configuration and models: changed only while stopped, under lifecycle (exclusive); pushing
	// frames holds it shared, so a frame never meets a half-built model.
	mutable std::shared_mutex lifecycle;
	mutable std::mutex pending_mutex;
	LiveRoomConfig pending;
	bool has_pending = false;
	LiveRoomConfig cfg;
	bool configured = false;
	std::string config_error;
	std::unique_ptr<DenseSlam> slam;
	std::unique_ptr<CoarsePipeline> coarse;
	std::unique_ptr<RoomMesh> own_room; // the room without a rig (no coarse pipeline)
	std::atomic<uint64_t> room_builds{ 0 }; // room_version()
	std::unique_ptr<ProbeRenderer> renderer; // built with the room (build_room_locked)
	std::mutex coarse_mutex; // the coarse pipeline: its worker, and finish()
	FisheyeLinearizer linearizer;
	std::array<float, 256> rgb_lut{};
	bool rgb_lut_active = false;
	// The newest RGB-D frame with its pose (room frame), for the coarse model's RGB texturing:
	// written by the SLAM side, taken by the coarse side at its next fisheye frame, or, without a
	// fisheye, as its next view (woken by pending_rgb_ready; offered every rgb_view_interval_s).
	struct PendingRgb {
		RgbdFrame frame;
		Pose world_from_rgb;
	};
	std::mutex pending_rgb_mutex;
	std::optional<PendingRgb> pending_rgb;
	std::condition_variable pending_rgb_ready;
	double next_rgb_view_s = -std::numeric_limits<double>::infinity(); // the SLAM side's
	// Without a fisheye: p_view into the coarse model as its view (CoarsePipeline::add_rgb_view).
	void process_rgb_view(const PendingRgb &p_view);
	// The SLAM side's posed frame for the coarse model: kept for its next fisheye frame, or
	// without a fisheye offered as a view (threaded: to the coarse worker; step mode: here).
	void offer_rgb(const RgbdFrame &p_frame, const Pose &p_world_from_rgb);
	std::optional<PendingRgb> take_rgb_view(std::chrono::milliseconds p_wait);
	// A view's snapshot made the newest, counted in counters.*p_counter, and the probes woken.
	void publish_coarse(std::shared_ptr<const CoarseSnapshot> p_snapshot, uint64_t LiveRoomStats::*p_counter);

	PoseHistory tracked; // the SLAM thread appends, the coarse thread reads (its own lock)
	DenseLighting dense_lighting; // thread-safe itself

	// Published results.
	mutable std::mutex publish_mutex;
	std::shared_ptr<const TrackedFrame> last_tracked;
	std::shared_ptr<const CoarseSnapshot> last_coarse;
	std::shared_ptr<const DenseMeshSnapshot> last_mesh;
	int fused_since_mesh = 0;
	bool remesh_due = false; // waiting for the mesh worker to take the last input

	DenseMeshStage mesh_stage; // thread-safe itself

	mutable std::mutex placer_mutex;
	SurfacePlacer placer;

	// Probes.
	mutable std::mutex probe_mutex;
	std::condition_variable probes_dirty;
	std::map<int, std::shared_ptr<Probe>> probes;
	int next_probe = 1;
	bool inputs_changed = false; // a new fused frame or coarse snapshot since the last render
	uint64_t input_generation = 0; // counts those changes
	uint64_t full_faces_generation = UINT64_MAX; // renders decided at or after it raycast all dense faces (finish())

	// Threads.
	std::atomic<bool> running{ false };
	std::atomic<bool> stopping{ false };
	std::unique_ptr<Frames> frames;
	std::thread slam_thread, coarse_thread, probe_thread, room_thread, mesh_thread;
	// The blocks the mesh worker meshes next. The SLAM thread puts one only when the last was
	// taken (the blocks changed meanwhile stay marked in the volume), so none is overwritten.
	Mailbox<std::shared_ptr<DenseMeshStage::Input>> mesh_inputs;

	RoomFinderStage room_finder; // the room from the sweep: its views and estimates, its own lock

	// Counters and latencies.
	mutable std::mutex stats_mutex;
	std::string compute_note = "CPU"; // stats().compute
	bool compute_on_device = false; // stats().compute_on_device, before tracking's share
	LiveRoomStats counters;
	std::vector<double> rgbd_latencies_ms, fisheye_latencies_ms;
	std::vector<std::pair<uint64_t, double>> rgbd_arrivals, fisheye_arrivals; // recent (sequence, push time)
	uint64_t rgbd_latency_seen = 0, fisheye_latency_seen = 0;
	std::atomic<uint64_t> rgbd_sequence{ 0 }, fisheye_sequence{ 0 };
};

} // namespace roomprobe
