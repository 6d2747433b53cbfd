// engine/live_room.h: the one live system. Step mode is the old sequential path (DenseSlam, the
// tracked trajectory, fisheye_pose_at, CoarsePipeline, the coarse render with the dense pass over
// it, SH) frame for frame; threaded mode ends with the same model; stopping is clean; probes, the
// room-only engine, configuration errors and engine/mailbox.h.
//
// The recording is the synthetic living room of synth_test_frames.h (the dense SLAM tests'
// fixture), 0.6 s of it: 18 RGB-D frames at 320x240 and 7 fisheye frames of a 256x256 fisheye,
// rendered once in memory and shared by the test cases.

#include <io/opencv.h>

#include "engine/live_room.h"
#include "engine/mailbox.h"
#include "envmap/coarse_render.h"
#include "envmap/dense_render.h"
#include "envmap/spherical_harmonics.h"
#include "pipeline/coarse_pipeline.h"
#include "rig/fisheye_pose.h"
#include "rig/photometry.h"
#include "room/reference_rooms.h"
#include "slam/dense_slam.h"
#include "engine_test_recording.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <chrono>
#include <cmath>
#include <optional>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <numbers>
#include <thread>
#include <vector>

using namespace roomprobe;
using namespace engine_test;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point p_start) {
	return std::chrono::duration<double>(Clock::now() - p_start).count();
}

constexpr int PROBE_SIZE = 32;

// ---------------------------------------------------------------- tolerances
//
// Step mode and the hand-driven old path run the very same functions on the very same inputs in
// the same order (the parallel loops in SLAM, the coarse model and the renderers split their work
// in fixed stripes or per texel, so no sum depends on the thread count), so they should agree
// bit for bit. The tolerances only allow a few float ULPs in case a compiler contracts an
// expression differently in another inlining context:
//   poses: float ICP on coordinates up to ~5 m: one ULP is 5 * 2^-23 = 6e-7 m; 1e-6 m ~ 2 ULPs.
//   quaternion components (|q| <= 1): one ULP of a float is 1.2e-7; 1e-6 ~ 8 ULPs.
//   cubemap texels: linear radiance up to ~2 (8-bit 255 over exposure 1, times at most 2 of
//   inverse vignetting at the fisheye's rim): one ULP is 2.4e-7; 1e-6 ~ 4 ULPs.
//   SH: c = sum_i f_i Y(w_i) dw_i, so by Cauchy-Schwarz |dc| <= max|df| sqrt(sum dw_i) sqrt(sum
//   Y^2 dw_i) = max|df| sqrt(4 pi) * 1 (normalised basis); 1.5x for the discrete quadrature.
constexpr double POSE_TOL_M = 1e-6;
constexpr double QUAT_TOL = 1e-6;
constexpr double TEXEL_TOL = 1e-6;
const double SH_TOL = 1.5 * TEXEL_TOL * std::sqrt(4.0 * std::numbers::pi);

// ---------------------------------------------------------------- the recording

// The recording and the engine configuration: engine_test_recording.h.

// ---------------------------------------------------------------- comparisons

double max_abs_diff(const Cubemap &p_a, const Cubemap &p_b) {
	REQUIRE(is_valid_cubemap(p_a));
	REQUIRE(is_valid_cubemap(p_b));
	REQUIRE(p_a.size == p_b.size);
	double worst = 0.0;
	for (int f = 0; f < 6; f++) {
		cv::Mat diff;
		cv::absdiff(p_a.faces[size_t(f)], p_b.faces[size_t(f)], diff);
		double m = 0.0;
		cv::minMaxLoc(diff.reshape(1), nullptr, &m);
		worst = std::max(worst, m);
	}
	return worst;
}

double mean_abs_diff(const Cubemap &p_a, const Cubemap &p_b) {
	double sum = 0.0;
	for (int f = 0; f < 6; f++) {
		cv::Mat diff;
		cv::absdiff(p_a.faces[size_t(f)], p_b.faces[size_t(f)], diff);
		const cv::Scalar s = cv::sum(diff);
		sum += s[0] + s[1] + s[2];
	}
	return sum / (6.0 * p_a.size * p_a.size * 3.0);
}

double mean_value(const Cubemap &p_map) {
	double sum = 0.0;
	for (int f = 0; f < 6; f++) {
		const cv::Scalar s = cv::sum(p_map.faces[size_t(f)]);
		sum += s[0] + s[1] + s[2];
	}
	return sum / (6.0 * p_map.size * p_map.size * 3.0);
}

double max_sh_diff(const ShCoefficients &p_a, const ShCoefficients &p_b) {
	double worst = 0.0;
	for (size_t i = 0; i < p_a.size(); i++) {
		for (int c = 0; c < 3; c++) {
			worst = std::max(worst, std::abs(p_a[i][c] - p_b[i][c]));
		}
	}
	return worst;
}

double max_atlas_diff(const cv::Mat &p_a, const cv::Mat &p_b) {
	REQUIRE(p_a.size() == p_b.size());
	REQUIRE(p_a.type() == p_b.type());
	cv::Mat diff;
	cv::absdiff(p_a, p_b, diff);
	double m = 0.0;
	cv::minMaxLoc(diff.reshape(1), nullptr, &m);
	return m;
}

// The forms made for display on the workers: the pushed RGB image with alpha 255, exactly; the
// atlas as half floats with alpha 1, within a half's rounding (2^-11 relative, 2^-24 absolute
// for the subnormals).
void check_display_forms(const TrackedFrame &p_tracked, const cv::Mat &p_pushed_rgb, const CoarseSnapshot &p_snapshot) {
	REQUIRE(p_tracked.rgba.mat.type() == CV_8UC4);
	REQUIRE(p_tracked.rgba.mat.size() == p_pushed_rgb.size());
	REQUIRE(p_tracked.rgba.bytes->data() == p_tracked.rgba.mat.data);
	cv::Mat channels[4];
	cv::split(p_tracked.rgba.mat, channels);
	cv::Mat rgb;
	cv::merge(channels, 3, rgb);
	CHECK(cv::norm(rgb, p_pushed_rgb, cv::NORM_INF) == 0.0);
	CHECK(cv::countNonZero(channels[3] != 255) == 0);
	REQUIRE(p_snapshot.display.mat.type() == CV_16FC4);
	REQUIRE(p_snapshot.display.mat.size() == p_snapshot.atlas.size());
	REQUIRE(p_snapshot.display.bytes->data() == p_snapshot.display.mat.data);
	cv::Mat shown;
	p_snapshot.display.mat.convertTo(shown, CV_32F);
	int outside = 0;
	for (int y = 0; y < shown.rows; y++) {
		for (int x = 0; x < shown.cols; x++) {
			const cv::Vec4f d = shown.at<cv::Vec4f>(y, x);
			const cv::Vec3f a = p_snapshot.atlas.at<cv::Vec3f>(y, x);
			for (int c = 0; c < 3; c++) {
				outside += std::abs(d[c] - a[c]) > std::abs(a[c]) * 0x1p-11f + 0x1p-24f;
			}
			outside += d[3] != 1.0f;
		}
	}
	CHECK(outside == 0);
}

void check_same_trajectory(const Trajectory &p_a, const Trajectory &p_b, double p_tol_m, double p_quat_tol) {
	REQUIRE(p_a.size() == p_b.size());
	double worst_m = 0.0, worst_q = 0.0;
	for (size_t i = 0; i < p_a.size(); i++) {
		const TimedPose &a = p_a.get_samples()[i], &b = p_b.get_samples()[i];
		CHECK(a.t_s == b.t_s);
		worst_m = std::max(worst_m, glm::length(a.world_from_camera.translation - b.world_from_camera.translation));
		for (int c = 0; c < 4; c++) {
			worst_q = std::max(worst_q, std::abs(a.world_from_camera.rotation[c] - b.world_from_camera.rotation[c]));
		}
	}
	CHECK(worst_m <= p_tol_m);
	CHECK(worst_q <= p_quat_tol);
}

// Polls p_done every few milliseconds for at most p_timeout_s; whether it came true.
bool wait_until(const std::function<bool()> &p_done, double p_timeout_s) {
	const Clock::time_point start = Clock::now();
	while (!p_done()) {
		if (seconds_since(start) > p_timeout_s) {
			return false;
		}
		std::this_thread::sleep_for(std::chrono::milliseconds(2));
	}
	return true;
}

// ---------------------------------------------------------------- step mode, once

struct StepResult {
	Trajectory trajectory;
	std::shared_ptr<const ProbeMap> map;
	cv::Mat atlas; // the published coarse snapshot's completed colour
	LiveRoomStats stats;
	std::shared_ptr<const DenseMeshSnapshot> mesh;
};

// The whole recording through one LiveRoom in step mode, then one probe rendered.
const StepResult &step_result() {
	static const std::unique_ptr<StepResult> result = [] {
		const Recording &rec = recording();
		auto out = std::make_unique<StepResult>();
		LiveRoom engine;
		const std::string error = engine.configure(live_config(rec));
		REQUIRE_MESSAGE(error.empty(), error);
		for (const Event &event : rec.events) {
			push_event(engine, rec, event);
		}
		engine.finish(); // step mode, synchronous inpainting: nothing to wait for
		const int probe = engine.add_probe(rec.probe, PROBE_SIZE);
		engine.render_probes();
		out->trajectory = engine.trajectory();
		out->map = engine.probe_map(probe);
		REQUIRE(out->map != nullptr);
		const auto snapshot = engine.coarse_snapshot();
		REQUIRE(snapshot != nullptr);
		out->atlas = snapshot->atlas;
		out->stats = engine.stats();
		out->mesh = engine.dense_mesh();
		return out;
	}();
	return *result;
}

} // namespace

// ---------------------------------------------------------------- 1. step mode = the old path

TEST_CASE("engine: step mode is the old sequential path (DenseSlam, fisheye_pose_at, CoarsePipeline, coarse + dense render, SH)") {
	const Recording &rec = recording();
	REQUIRE(rec.rgbd.size() == size_t(RGBD_FRAMES));
	REQUIRE(rec.fisheye.size() >= 6);
	const LiveRoomConfig cfg = live_config(rec);
	const StepResult &step = step_result();

	// (b) the old path by hand.
	DenseSlam slam(cfg.slam);
	REQUIRE(slam.configure(rec.rig.rgb, rec.initial_rgb_pose) == "");
	slam.volume().set_keep_points(cfg.keep_points);
	FisheyeLinearizer linearizer;
	linearizer.configure(rec.photometry, rec.rig.fisheye);
	REQUIRE(linearizer.active());
	CoarsePipelineOptions options = cfg.coarse;
	options.pose_source = PoseSource::Tracked;
	options.lighting_options.saturated_threshold = std::numeric_limits<float>::infinity();
	options.lighting_options.black_threshold = linearizer.centre_radiance(5);
	CoarsePipeline coarse(options);
	REQUIRE(coarse.configure(rec.rig, rec.floorplan) == "");
	Trajectory trajectory;
	size_t fisheye_used = 0;
	std::optional<std::pair<RgbdFrame, Pose>> pending_rgb;
	const ResponseCurve rgb_lut_for_coarse = rgb_radiance_lut(rec.photometry);
	DenseLighting lighting; // the lighting each fused frame's colours were of
	for (const Event &event : rec.events) {
		if (!event.fisheye) {
			const RgbdFrame &frame = rec.rgbd[event.index];
			const DenseSlamFrame out = slam.process(frame);
			if (out.integrated) {
				lighting.record(slam.volume().frame_count(), coarse.cumulative_lighting());
			}
			INFO("RGB-D frame ", event.index, ": ", out.tracking.reason);
			CHECK(out.tracking.state == TrackingState::Good); // the fixture tracks (test_slam_dense.cpp)
			if (out.tracking.state != TrackingState::Lost) {
				std::string error;
				CHECK(trajectory.append({ frame.timestamp_s, slam.pose() }, &error));
				pending_rgb = std::make_pair(frame, slam.pose()); // the coarse model's RGB texturing, at its next frame
			}
			continue;
		}
		const FisheyeFrame &frame = rec.fisheye[event.index];
		Pose pose;
		std::string error;
		if (trajectory.is_empty() || !fisheye_pose_at(trajectory, rec.rig, frame.timestamp_s, &pose, &error, 0.1)) {
			continue;
		}
		FisheyeFrame linear = frame;
		LinearFrame radiance = linearizer.linearise(frame.image);
		linear.image = radiance.radiance;
		linear.saturated = radiance.saturated;
		linear.hdr = linear.image.type() == CV_32FC3;
		CHECK(linear.hdr);
		if (pending_rgb) {
			coarse.add_rgb_frame(pending_rgb->first, rec.rig.rgb, pending_rgb->second, rec.photometry.known ? &rgb_lut_for_coarse : nullptr);
			pending_rgb.reset();
		}
		coarse.add_fisheye_frame(linear, pose);
		fisheye_used++;
	}
	CHECK(fisheye_used == rec.fisheye.size()); // the first fisheye frame follows the first RGB-D frame
	const CoarseCubemapRenderer renderer(coarse.mesh());
	Cubemap expected = renderer.render(coarse.completed_color(), rec.probe, PROBE_SIZE);
	REQUIRE(is_valid_cubemap(expected));
	const ResponseCurve rgb_lut = rgb_radiance_lut(rec.photometry);
	DenseRenderOptions dense_options;
	dense_options.scale = cfg.dense_render_scale;
	dense_options.lut = &rgb_lut;
	// The shell first (dense_render.h): the texels the fisheye observed, rendered like the atlas.
	cv::Mat observed_atlas;
	cv::Mat(coarse.texture().quality > 0.0f).convertTo(observed_atlas, CV_32F, 1.0 / 255.0);
	const std::array<cv::Mat, 6> observed = renderer.render_channel(observed_atlas, rec.probe, PROBE_SIZE);
	dense_options.coarse_observed = &observed;
	const DenseRenderStats dense_stats =
			lighting.render_over(slam.volume(), coarse.cumulative_lighting(), rec.probe, dense_options, &expected);
	CHECK(dense_stats.texels_covered > 0); // the table below the probe is in the dense model
	const ShCoefficients expected_sh = project_sh(expected);

	// (a) against the engine in step mode.
	check_same_trajectory(step.trajectory, trajectory, POSE_TOL_M, QUAT_TOL);
	CHECK(step.stats.rgbd_processed == rec.rgbd.size());
	CHECK(step.stats.good == rec.rgbd.size());
	CHECK(step.stats.fisheye_integrated == fisheye_used);
	CHECK(step.stats.fisheye_without_pose == 0);
	CHECK(step.stats.stage_errors == 0);
	CHECK(step.stats.dense_fused == slam.integrated_count());
	CHECK(max_atlas_diff(step.atlas, coarse.completed_color()) <= TEXEL_TOL);
	const ProbeMap &map = *step.map;
	CHECK(map.rgbd_sequence == rec.rgbd.size());
	CHECK(map.fisheye_sequence == rec.fisheye.size());
	CHECK(map.dense.texels_covered == dense_stats.texels_covered);
	const double texel_diff = max_abs_diff(map.cubemap, expected);
	const double sh_diff = max_sh_diff(map.sh, expected_sh);
	MESSAGE("step mode vs the old path: max texel diff ", texel_diff, ", max SH diff ", sh_diff, ", dense texels ", dense_stats.texels_covered,
			", mean radiance ", mean_value(expected));
	CHECK(texel_diff <= TEXEL_TOL);
	CHECK(sh_diff <= SH_TOL);
	CHECK(mean_value(expected) > 0.01); // not a black map compared with a black map
	// The dense mesh is published every mesh_interval_frames (15) fused frames: once in 18.
	REQUIRE(step.mesh != nullptr);
	CHECK(step.mesh->version == 1);
	REQUIRE(step.mesh->mesh != nullptr);
	CHECK_FALSE(step.mesh->mesh->vertices.empty());
	// The display's regions partition the whole mesh: every triangle in exactly one region.
	size_t region_triangles = 0;
	for (const DenseMeshChunk &chunk : step.mesh->chunks) {
		REQUIRE(chunk.mesh != nullptr);
		CHECK_FALSE(chunk.mesh->indices.empty());
		region_triangles += chunk.mesh->indices.size() / 3;
	}
	CHECK(region_triangles == step.mesh->mesh->indices.size() / 3);
}

// ---------------------------------------------------------------- 2. threaded = step mode

// The frames are pushed at the pace the workers take them: each push waits until its stage has
// finished the frame (the engine's own counters). A sleep-based pace would drop frames on a
// loaded two-core machine; this one makes the threaded engine see every frame, in the same order
// as step mode, so it must end with the same model: the same trajectory and the same coarse atlas
// (same tolerances as test 1, same argument). The threaded engine inpaints asynchronously, as the
// live nodes configure it (CoarseRoomModel, the benchmark): its observed texels are the same, and
// once finish() has composed the worker's last completion the completed atlas is the synchronous
// one (test_pipeline_coarse.cpp). The probe map then is step mode's too, to the same tolerance:
//   - its coarse part is the same atlas rendered at the same point;
//   - its dense part is the same volume, times DenseLighting's changes: the SLAM stage records the
//     coarse lighting after each fused frame, and the pacing makes that the same coarse state in
//     both modes (every earlier fisheye frame is in it), so the epochs are the same; the final
//     render takes them to the final coarse lighting in both.
// Maps the worker rendered before finish() composed the last completion show the older fill in
// never-observed texels; finish() waits for a map rendered after it, so the map it leaves must match.
TEST_CASE("engine: threaded mode, paced so that no frame is dropped, ends with step mode's model") {
	const Recording &rec = recording();
	REQUIRE_FALSE(rec.events.back().fisheye); // the argument above
	const StepResult &step = step_result();
	LiveRoomConfig cfg = live_config(rec);
	cfg.coarse.inpaint_async = true;
	LiveRoom engine;
	REQUIRE(engine.configure(cfg) == "");
	const int probe = engine.add_probe(rec.probe, PROBE_SIZE);
	REQUIRE(engine.start());
	REQUIRE(engine.is_running());
	CHECK(engine.start()); // a no-op when running
	CHECK(engine.slam_model() == nullptr); // step mode only
	CHECK(engine.coarse_model() == nullptr);
	const Clock::time_point start = Clock::now();
	size_t rgbd = 0, fisheye = 0;
	for (const Event &event : rec.events) {
		push_event(engine, rec, event);
		if (event.fisheye) {
			fisheye++;
			REQUIRE_MESSAGE(wait_until([&] {
				const LiveRoomStats s = engine.stats();
				return s.fisheye_integrated + s.fisheye_without_pose >= fisheye;
			}, 30.0), "fisheye frame ", event.index, " was never taken");
		} else {
			rgbd++;
			REQUIRE_MESSAGE(wait_until([&] { return engine.stats().rgbd_processed >= rgbd; }, 30.0), "RGB-D frame ", event.index, " was never taken");
		}
	}
	engine.finish();
	// finish() publishes the final atlas and waits for every probe's map of it: the map is final now.
	std::shared_ptr<const ProbeMap> map = engine.probe_map(probe);
	const bool converged = map && map->rgbd_sequence == rec.rgbd.size() && map->fisheye_sequence == rec.fisheye.size() &&
			max_abs_diff(map->cubemap, step.map->cubemap) <= TEXEL_TOL;
	REQUIRE(map != nullptr);
	CHECK(converged);
	const double threaded_s = seconds_since(start);
	const LiveRoomStats stats = engine.stats();
	CHECK(stats.running);
	engine.stop();
	CHECK_FALSE(engine.is_running());
	map = engine.probe_map(probe); // the worker's last map: nothing rendered after the matching one undid it
	// The mesh worker meshed the blocks the SLAM worker copied (frame 15), then built its Embree scene
	// from that mesh: rays down onto its triangles meet the dense model (those on a wall may meet the room).
	const std::shared_ptr<const DenseMeshSnapshot> dense = engine.dense_mesh();
	REQUIRE(dense != nullptr);
	REQUIRE(dense->mesh != nullptr);
	const TriangleMesh &triangles = *dense->mesh;
	REQUIRE(triangles.indices.size() >= 300);
	int on_dense = 0;
	for (size_t t = 0; t + 2 < triangles.indices.size(); t += triangles.indices.size() / 100 / 3 * 3) {
		const glm::dvec3 a(triangles.vertices[triangles.indices[t]]), b(triangles.vertices[triangles.indices[t + 1]]), c(triangles.vertices[triangles.indices[t + 2]]);
		const glm::dvec3 normal = glm::normalize(glm::cross(b - a, c - a));
		const PlacementHit hit = engine.place_ray((a + b + c) / 3.0 + 0.05 * normal, -normal, 1.0);
		on_dense += hit.surface == PlacementSurface::Dense && hit.distance_m <= 0.05 + 1e-4;
	}
	MESSAGE(on_dense, " of 100 rays onto the published mesh met the dense model");
	CHECK(on_dense >= 50);
	MESSAGE("threaded run: ", threaded_s, " s, ", stats.probe_renders, " probe renders; RGB-D latency p50 ", stats.rgbd_latency.p50_ms,
			" ms, fisheye latency p50 ", stats.fisheye_latency.p50_ms, " ms");

	CHECK(stats.rgbd_pushed == rec.rgbd.size());
	CHECK(stats.rgbd_processed == rec.rgbd.size());
	CHECK(stats.rgbd_dropped == 0);
	CHECK(stats.fisheye_dropped == 0);
	CHECK(stats.fisheye_integrated == step.stats.fisheye_integrated);
	CHECK(stats.fisheye_without_pose == step.stats.fisheye_without_pose);
	CHECK(stats.good == step.stats.good);
	CHECK(stats.stage_errors == 0);
	CHECK(stats.probe_renders >= 1);
	CHECK(stats.rgbd_latency.count >= 1);

	check_same_trajectory(engine.trajectory(), step.trajectory, POSE_TOL_M, QUAT_TOL);
	const auto tracked = engine.tracked_frame();
	REQUIRE(tracked != nullptr);
	CHECK(tracked->sequence == rec.rgbd.size());
	CHECK(glm::length(tracked->world_from_camera.translation - step.trajectory.get_samples().back().world_from_camera.translation) <= POSE_TOL_M);
	const auto snapshot = engine.coarse_snapshot();
	REQUIRE(snapshot != nullptr);
	CHECK(snapshot->frames == step.stats.fisheye_integrated);
	CHECK(max_atlas_diff(snapshot->atlas, step.atlas) <= TEXEL_TOL);
	check_display_forms(*tracked, rec.rgbd.back().rgb, *snapshot);

	const double texel_diff = max_abs_diff(map->cubemap, step.map->cubemap);
	MESSAGE("threaded vs step probe map: max texel diff ", texel_diff, ", mean ", mean_abs_diff(map->cubemap, step.map->cubemap), " (version ",
			map->version, ")");
	CHECK(map->rgbd_sequence == rec.rgbd.size());
	CHECK(map->fisheye_sequence == rec.fisheye.size());
	CHECK(texel_diff <= TEXEL_TOL);
	CHECK(max_sh_diff(map->sh, step.map->sh) <= SH_TOL);
	CHECK(map->dense.texels_covered == step.map->dense.texels_covered); // the same fused model seen from the same point
}

// ---------------------------------------------------------------- 3. stopping

// stop() closes the mailboxes and joins; each worker finishes at most the item in hand: one SLAM
// frame at 320x240, one coarse frame (a fisheye frame waiting for its pose looks at the stop flag
// every 10 ms, whatever fisheye_pose_wait_s is; then the update and inpainting of a 0.05 m atlas
// of ~35k texels) or one 32x32 probe render: each well under half a second in the debug build,
// plus the workers' 50 ms poll. 2 s allows that 4x over on a machine shared with a build.
constexpr double STOP_LIMIT_S = 2.0;

// Starts p_engine and gets every worker busy: the first few frames one at a time, until all three
// workers have had work (a fused RGB-D frame, an integrated fisheye frame, a probe map; pushed in a
// burst, the newest RGB-D frame would replace the first and the first fisheye frame would find no
// pose yet), then the rest as fast as possible.
void start_busy(LiveRoom &p_engine, const Recording &p_rec, int p_probe) {
	REQUIRE(p_engine.start());
	size_t next = 0;
	for (; next < 5; next++) {
		push_event(p_engine, p_rec, p_rec.events[next]);
		const size_t rgbd = p_engine.stats().rgbd_pushed, fisheye = p_engine.stats().fisheye_pushed;
		REQUIRE(wait_until([&] {
			const LiveRoomStats s = p_engine.stats();
			return s.rgbd_processed >= rgbd && s.fisheye_integrated + s.fisheye_without_pose >= fisheye;
		}, 30.0));
	}
	REQUIRE(p_engine.stats().fisheye_integrated >= 1);
	REQUIRE(wait_until([&] { return p_engine.probe_map(p_probe) != nullptr; }, 30.0));
	for (; next < p_rec.events.size(); next++) {
		push_event(p_engine, p_rec, p_rec.events[next]);
	}
}

TEST_CASE("engine: stop() while every worker is busy returns promptly; destroying a running engine is clean") {
	const Recording &rec = recording();
	LiveRoomConfig cfg = live_config(rec);
	cfg.coarse.inpaint_async = true; // as the live nodes: the inpainting worker is busy too
	LiveRoom engine;
	REQUIRE(engine.configure(cfg) == "");
	const int probe = engine.add_probe(rec.probe, PROBE_SIZE);
	start_busy(engine, rec, probe);
	Clock::time_point start = Clock::now();
	engine.stop();
	const double stop_s = seconds_since(start);
	MESSAGE("stop() took ", stop_s, " s");
	CHECK(stop_s < STOP_LIMIT_S);
	CHECK_FALSE(engine.is_running());
	const LiveRoomStats stopped = engine.stats();
	CHECK_FALSE(stopped.running);
	CHECK(stopped.stage_errors == 0);
	CHECK(stopped.rgbd_processed + stopped.rgbd_dropped <= stopped.rgbd_pushed);
	CHECK(stopped.rgbd_processed < stopped.rgbd_pushed); // it was stopped with frames in hand or waiting
	engine.stop(); // twice is harmless

	// After stop, pushing is step mode again: processed before push returns.
	const LiveRoomStats before = engine.stats();
	engine.push_rgbd(rec.rgbd.back());
	const LiveRoomStats after = engine.stats();
	CHECK(after.rgbd_processed == before.rgbd_processed + 1);
	REQUIRE(engine.tracked_frame() != nullptr);
	CHECK(engine.tracked_frame()->sequence == after.rgbd_pushed);
	engine.push_fisheye(rec.fisheye.back());
	const LiveRoomStats after_fisheye = engine.stats();
	CHECK(after_fisheye.fisheye_integrated + after_fisheye.fisheye_without_pose == after.fisheye_integrated + after.fisheye_without_pose + 1);
	const uint64_t version = engine.probe_map(probe)->version;
	engine.render_probes();
	CHECK(engine.probe_map(probe)->version == version + 1);
	CHECK(engine.probe_map(probe)->rgbd_sequence == after.rgbd_pushed);
	CHECK(engine.slam_model() != nullptr);
	CHECK(engine.coarse_model() != nullptr);

	// Destroyed while running, mid-burst.
	start = Clock::now();
	{
		auto running = std::make_unique<LiveRoom>();
		REQUIRE(running->configure(cfg) == "");
		start_busy(*running, rec, running->add_probe(rec.probe, PROBE_SIZE));
		start = Clock::now();
		running.reset();
	}
	const double destroy_s = seconds_since(start);
	MESSAGE("destroying a running engine took ", destroy_s, " s");
	CHECK(destroy_s < STOP_LIMIT_S);
}

TEST_CASE("engine: configure() while running stops the workers; reconfigure() restarts them") {
	const Recording &rec = recording();
	LiveRoom engine;
	CHECK_FALSE(engine.start()); // not configured
	REQUIRE(engine.configure(live_config(rec)) == "");
	REQUIRE(engine.start());
	engine.push_rgbd(rec.rgbd[0]);
	REQUIRE(wait_until([&] { return engine.stats().rgbd_processed >= 1; }, 30.0));
	REQUIRE(engine.configure(live_config(rec)) == "");
	CHECK_FALSE(engine.is_running());
	CHECK_FALSE(engine.stats().running);
	CHECK(engine.stats().rgbd_processed == 0); // a fresh model
	CHECK(engine.trajectory().is_empty());
	// Stopped by configure: pushing is step mode. A fisheye frame before any tracked pose is skipped,
	// never integrated at a guess, and says why.
	engine.push_fisheye(rec.fisheye[0]);
	CHECK(engine.stats().fisheye_without_pose == 1);
	CHECK(engine.stats().fisheye_integrated == 0);
	CHECK(engine.stats().fisheye_pose_problem.find("no tracked RGB-D pose") != std::string::npos);
	engine.push_rgbd(rec.rgbd[0]);
	CHECK(engine.stats().rgbd_processed == 1);
	CHECK(engine.trajectory().size() == 1);
	engine.push_fisheye(rec.fisheye[0]);
	CHECK(engine.stats().fisheye_integrated == 1);

	REQUIRE(engine.start());
	const std::string error = engine.reconfigure([](LiveRoomConfig &p_cfg) { p_cfg.mesh_interval_frames = 5; });
	CHECK(error == "");
	CHECK(engine.is_running()); // restarted
	CHECK(engine.config().mesh_interval_frames == 5);
	engine.stop();
	CHECK_FALSE(engine.is_running());
}

// ---------------------------------------------------------------- 4. probes, atlas, room only

namespace {

LiveRoomConfig room_only_config() {
	LiveRoomConfig cfg;
	cfg.has_rig = false;
	cfg.dense = false;
	cfg.has_room = true;
	cfg.floorplan = living_room(); // 5 m x 4 m x 2.5 m
	cfg.coarse.texel_size_m = 0.05;
	return cfg;
}

// Texels of a square RGBA-half mip chain from p_size down to 1x1 (each level half the last,
// rounded down, at least 1: Godot's rule), times 4 uint16 (8 bytes) per texel.
size_t mip_chain_uint16(int p_size) {
	size_t texels = 0;
	for (int s = p_size;; s = std::max(1, s / 2)) {
		texels += size_t(s) * size_t(s);
		if (s == 1) {
			break;
		}
	}
	return texels * 8 / 2;
}

float half_to_float(uint16_t p_half) {
	cv::Mat h(1, 1, CV_16FC1);
	h.at<uint16_t>(0, 0) = p_half;
	cv::Mat f;
	h.convertTo(f, CV_32F);
	return f.at<float>(0, 0);
}

} // namespace

TEST_CASE("engine: probes are added, moved and removed; maps carry versions and Godot's RGBA-half mip chain") {
	const glm::dvec3 centre(2.5, 1.2, 2.0);
	CHECK(mip_chain_uint16(32) == size_t(1024 + 256 + 64 + 16 + 4 + 1) * 4);
	CHECK(mip_chain_uint16(24) == size_t(576 + 144 + 36 + 9 + 1) * 4);
	CHECK(gpu_face_bytes(24) == mip_chain_uint16(24) * sizeof(uint16_t));

	LiveRoom engine;
	CHECK(engine.set_atlas(cv::Mat(4, 4, CV_32FC3)) == false); // no room yet
	REQUIRE(engine.configure(room_only_config()) == "");
	const RoomMesh *mesh = engine.room_mesh();
	REQUIRE(mesh != nullptr);
	CHECK_FALSE(engine.start()); // no rig: nothing to run
	CHECK_FALSE(engine.is_running());

	// Atlases of the wrong size or type are refused.
	CHECK_FALSE(engine.set_atlas(cv::Mat(mesh->atlas_height, mesh->atlas_width + 1, CV_32FC3, cv::Scalar::all(0.5))));
	CHECK_FALSE(engine.set_atlas(cv::Mat(mesh->atlas_height + 1, mesh->atlas_width, CV_32FC3, cv::Scalar::all(0.5))));
	CHECK_FALSE(engine.set_atlas(cv::Mat(mesh->atlas_height, mesh->atlas_width, CV_8UC3, cv::Scalar::all(128))));
	CHECK_FALSE(engine.set_atlas(cv::Mat()));
	CHECK(engine.coarse_snapshot() == nullptr);

	// Before any atlas the map is black (no observation yet).
	const int a = engine.add_probe(centre, 32);
	const int b = engine.add_probe(centre + glm::dvec3(1.0, 0.0, 0.0), 24);
	CHECK(a != b);
	CHECK(engine.probe_map(a) == nullptr);
	engine.render_probes();
	REQUIRE(engine.probe_map(a) != nullptr);
	CHECK(engine.probe_map(a)->version == 1);
	CHECK(engine.probe_map(b)->version == 1);
	CHECK(max_abs_diff(engine.probe_map(a)->cubemap, make_cubemap(32)) == 0.0);

	// A constant atlas: a constant map on every wall, the floor and the ceiling. Bilinear sampling of
	// a constant is the constant times weights that sum to 1: a few float ULPs (value 0.25..0.75,
	// ULP 6e-8) at most; 1e-6 bounds it.
	const cv::Vec3f colour(0.25f, 0.5f, 0.75f);
	REQUIRE(engine.set_atlas(cv::Mat(mesh->atlas_height, mesh->atlas_width, CV_32FC3, cv::Scalar(colour[0], colour[1], colour[2]))));
	REQUIRE(engine.coarse_snapshot() != nullptr);
	engine.render_probes();
	const auto map_a = engine.probe_map(a), map_b = engine.probe_map(b);
	REQUIRE(map_a != nullptr);
	REQUIRE(map_b != nullptr);
	CHECK(map_a->version == 2);
	CHECK(map_b->version == 2);
	CHECK(map_a->probe == a);
	CHECK(map_a->position == centre);
	CHECK(map_a->cubemap.size == 32);
	CHECK(map_b->cubemap.size == 24);
	CHECK(max_abs_diff(map_a->cubemap, make_cubemap(32, colour)) <= 1e-6);
	CHECK(max_abs_diff(map_b->cubemap, make_cubemap(24, colour)) <= 1e-6);
	CHECK(map_a->rgbd_sequence == 0);
	CHECK(map_a->fisheye_sequence == 0);
	// SH of a constant L: only c_0 = L * 4 pi * Y_0^0 = L * 2 sqrt(pi). project_sh weighs texels by
	// their exact solid angles, which tile the sphere (sum 4 pi up to double rounding), and the
	// texels are L within 1e-6 (2e-6 relative): 1e-5 relative bounds it.
	CHECK(map_a->sh[0].y == doctest::Approx(0.5 * 2.0 * std::sqrt(std::numbers::pi)).epsilon(1e-5));
	CHECK(std::abs(map_a->sh[1].y) < 1e-5); // no gradient in a constant (|Y_1| < 0.5, same bound)

	// gpu_faces: level 0 first, then each half-size level down to 1x1, RGBA halves; alpha is the
	// distance to the surface (envmap/parallax.h), area-averaged down the chain.
	for (const auto &map : { map_a, map_b }) {
		for (int f = 0; f < 6; f++) {
			CHECK(map->gpu_faces[size_t(f)]->size() == mip_chain_uint16(map->cubemap.size) * sizeof(uint16_t));
		}
	}
	std::vector<uint16_t> face(map_a->gpu_faces[0]->size() / sizeof(uint16_t));
	std::memcpy(face.data(), map_a->gpu_faces[0]->data(), map_a->gpu_faces[0]->size());
	// Half floats have an 11-bit significand: relative error <= 2^-11 = 4.9e-4 on rounding.
	for (int c = 0; c < 3; c++) {
		CHECK(half_to_float(face[size_t(c)]) == doctest::Approx(colour[c]).epsilon(1e-3));
		CHECK(half_to_float(face[face.size() - 4 + size_t(c)]) == doctest::Approx(colour[c]).epsilon(1e-3)); // the 1x1 level
	}
	RoomRayHit corner_hit;
	REQUIRE(intersect_room(*mesh, centre, cubemap_direction(0, 0.0, 0.0, 32), &corner_hit));
	REQUIRE(has_distances(map_a->cubemap));
	CHECK(map_a->cubemap.distance_m[0].at<float>(0, 0) == doctest::Approx(corner_hit.distance).epsilon(1e-6));
	CHECK(half_to_float(face[3]) == doctest::Approx(corner_hit.distance).epsilon(1e-3));
	CHECK(half_to_float(face.back()) == doctest::Approx(cv::mean(map_a->cubemap.distance_m[0])[0]).epsilon(1e-3));

	// set_probe: a move or resize re-renders at the new place; the same values change nothing.
	engine.set_probe(a, centre + glm::dvec3(0.0, 0.5, 0.0), 16);
	engine.render_probe(a);
	CHECK(engine.probe_map(a)->version == 3);
	CHECK(engine.probe_map(a)->cubemap.size == 16);
	CHECK(engine.probe_map(a)->position.y == doctest::Approx(1.7));
	CHECK(engine.probe_map(a)->gpu_faces[5]->size() == mip_chain_uint16(16) * sizeof(uint16_t));
	CHECK(engine.probe_map(b)->version == 2); // render_probe renders one
	engine.set_probe(a, centre, 0); // sizes are clamped to 1..4096
	engine.render_probe(a);
	CHECK(engine.probe_map(a)->cubemap.size == 1);
	CHECK(engine.probe_map(a)->gpu_faces[0]->size() == 8u);
	engine.set_probe(12345, centre, 8); // unknown: ignored
	CHECK_FALSE(engine.render_probe(12345));
	// probe_is_current (the editor renders only then): a rendered probe is, until it moves.
	CHECK(engine.probe_is_current(a));
	engine.set_probe(a, centre, 1); // the same place and size
	CHECK(engine.probe_is_current(a));
	engine.set_probe(a, centre + glm::dvec3(0.1, 0.0, 0.0), 1);
	CHECK_FALSE(engine.probe_is_current(a));
	engine.render_probe(a);
	CHECK(engine.probe_is_current(a));
	engine.set_probe(a, centre, 1);
	engine.render_probe(a);
	CHECK_FALSE(engine.probe_is_current(12345));

	// remove_probe: gone, its map too; the other stays.
	engine.remove_probe(a);
	CHECK(engine.probe_map(a) == nullptr);
	CHECK_FALSE(engine.render_probe(a));
	engine.render_probes();
	CHECK(engine.probe_map(b)->version == 3);
	const int c = engine.add_probe(centre, 8);
	CHECK(c != a); // ids are not reused
	CHECK(c != b);

	// One-off maps: any size in 1..4096, the same atlas.
	CHECK(engine.render_at(centre, 0).size == 0);
	CHECK(max_abs_diff(engine.render_at(centre, 16), make_cubemap(16, colour)) <= 1e-6);

	// configure() keeps the probes (their maps go) and their versions keep increasing, so a reader
	// that compares versions never takes a new map for an old one.
	REQUIRE(engine.configure(room_only_config()) == "");
	CHECK(engine.probe_map(b) == nullptr);
	CHECK(engine.coarse_snapshot() == nullptr); // the atlas went with the old room
	CHECK(engine.render_probe(b));
	REQUIRE(engine.probe_map(b) != nullptr);
	CHECK(engine.probe_map(b)->version == 4);
	CHECK(max_abs_diff(engine.probe_map(b)->cubemap, make_cubemap(24)) == 0.0);

	// Frames without a rig are ignored.
	RgbdFrame frame;
	frame.rgb = cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(0));
	frame.depth_m = cv::Mat(240, 320, CV_32FC1, cv::Scalar(1.0f));
	engine.push_rgbd(frame);
	CHECK(engine.stats().rgbd_processed == 0);
	CHECK(engine.tracked_frame() == nullptr);
}

// ---------------------------------------------------------------- 5. configuration errors

// A host's buffers for the faces (Godot's PackedByteArray in the extension): the faces are
// filled into them, with the same bytes as the default vectors; a factory that gives none, or
// one of the wrong size, leaves the face in a vector.
namespace {
struct HostBuffer final : PixelBuffer {
	explicit HostBuffer(size_t p_bytes) :
			bytes(p_bytes, 0xAB) {}
	uint8_t *data() override { return bytes.data(); }
	const uint8_t *data() const override { return bytes.data(); }
	size_t size() const override { return bytes.size(); }
	std::vector<uint8_t> bytes;
};
} // namespace

TEST_CASE("engine: the images for display are filled into the host's buffers when it gives them") {
	const glm::dvec3 centre(2.5, 1.2, 2.0);
	std::atomic<int> made{ 0 };
	LiveRoomConfig with_host = room_only_config();
	with_host.display_buffers = [&](size_t p_bytes) -> std::shared_ptr<PixelBuffer> {
		made++;
		return std::make_shared<HostBuffer>(p_bytes);
	};
	LiveRoomConfig refusing = room_only_config();
	refusing.display_buffers = [](size_t p_bytes) -> std::shared_ptr<PixelBuffer> { return std::make_shared<HostBuffer>(p_bytes + 1); };
	std::vector<std::shared_ptr<const ProbeMap>> maps;
	std::vector<std::shared_ptr<const CoarseSnapshot>> atlases;
	for (const LiveRoomConfig &cfg : { room_only_config(), with_host, refusing }) {
		LiveRoom engine;
		REQUIRE(engine.configure(cfg) == "");
		const RoomMesh *mesh = engine.room_mesh();
		REQUIRE(mesh != nullptr);
		REQUIRE(engine.set_atlas(cv::Mat(mesh->atlas_height, mesh->atlas_width, CV_32FC3, cv::Scalar(0.25, 0.5, 0.75))));
		const int probe = engine.add_probe(centre, 16);
		REQUIRE(engine.render_probe(probe));
		maps.push_back(engine.probe_map(probe));
		atlases.push_back(engine.coarse_snapshot());
		REQUIRE(maps.back() != nullptr);
		REQUIRE(atlases.back() != nullptr);
	}
	CHECK(made == 7); // the atlas shown, and the six faces
	CHECK(dynamic_cast<const HostBuffer *>(atlases[1]->display.bytes.get()) != nullptr);
	CHECK(dynamic_cast<const VectorPixelBuffer *>(atlases[2]->display.bytes.get()) != nullptr);
	for (size_t m = 1; m < 3; m++) {
		REQUIRE(atlases[m]->display.bytes->size() == atlases[0]->display.bytes->size());
		CHECK(std::memcmp(atlases[m]->display.bytes->data(), atlases[0]->display.bytes->data(), atlases[0]->display.bytes->size()) == 0);
	}
	for (size_t f = 0; f < 6; f++) {
		CHECK(dynamic_cast<const HostBuffer *>(maps[1]->gpu_faces[f].get()) != nullptr);
		CHECK(dynamic_cast<const VectorPixelBuffer *>(maps[2]->gpu_faces[f].get()) != nullptr);
		for (size_t m = 1; m < 3; m++) {
			REQUIRE(maps[m]->gpu_faces[f]->size() == maps[0]->gpu_faces[f]->size());
			CHECK(std::memcmp(maps[m]->gpu_faces[f]->data(), maps[0]->gpu_faces[f]->data(), maps[0]->gpu_faces[f]->size()) == 0);
		}
	}
}

TEST_CASE("engine: configuration errors name the problem") {
	LiveRoomConfig rig_and_room;
	rig_and_room.rig = test_rig();
	rig_and_room.rig.rgb = synth_frames::half_camera();
	rig_and_room.has_room = true;
	rig_and_room.floorplan = living_room();

	auto refused = [](const LiveRoomConfig &p_cfg, const std::string &p_expected) {
		LiveRoom engine;
		const std::string error = engine.configure(p_cfg);
		INFO("error: ", error);
		CHECK(error.find(p_expected) != std::string::npos);
		CHECK_FALSE(engine.is_configured());
		CHECK(engine.configuration_error() == error);
		CHECK_FALSE(engine.start());
		return error;
	};

	LiveRoomConfig cfg = rig_and_room;
	cfg.dense = false;
	cfg.coarse_poses = PoseSource::Tracked;
	const std::string tracked_error = refused(cfg, "tracked poses");
	CHECK(tracked_error.find("dense SLAM is off") != std::string::npos);

	cfg = rig_and_room;
	cfg.dense = false;
	cfg.coarse_poses = PoseSource::GroundTruth; // and no ground_truth
	refused(cfg, "no ground-truth RGB-D trajectory");
	cfg = rig_and_room;
	cfg.dense = true;
	cfg.dense_poses = PoseSource::GroundTruth;
	refused(cfg, "no ground-truth RGB-D trajectory");

	cfg = rig_and_room;
	cfg.dense = false;
	cfg.has_room = false;
	refused(cfg, "nothing to model");

	cfg = rig_and_room;
	cfg.has_rig = false;
	cfg.dense = true;
	refused(cfg, "dense SLAM needs a rig");

	cfg = rig_and_room;
	cfg.rig.rgb.fx = 0.0;
	refused(cfg, "rgb.fx");

	// A refused configuration leaves the engine unconfigured; a good one clears the error.
	LiveRoom engine;
	REQUIRE(engine.configure(rig_and_room) == "");
	CHECK(engine.is_configured());
	cfg = rig_and_room;
	cfg.dense = false;
	CHECK(engine.configure(cfg) != "");
	CHECK_FALSE(engine.is_configured());
	CHECK(engine.room_mesh() == nullptr);
	CHECK(engine.configure(rig_and_room) == "");
	CHECK(engine.is_configured());
	CHECK(engine.configuration_error() == "");
}

// ---------------------------------------------------------------- 6. the mailbox

TEST_CASE("engine: the mailbox keeps the newest value, counts the dropped, and close() wakes a waiting take") {
	Mailbox<int> box;
	CHECK_FALSE(box.pending());
	box.put(1);
	box.put(2);
	CHECK(box.pending());
	CHECK(box.dropped_count() == 1);
	CHECK(box.put_count() == 2);
	const std::optional<int> newest = box.take(std::chrono::milliseconds(0));
	REQUIRE(newest.has_value());
	CHECK(*newest == 2);
	CHECK_FALSE(box.pending());
	CHECK_FALSE(box.try_take().has_value());
	CHECK(box.dropped_count() == 1); // taking drops nothing

	// A take waiting 10 s returns as soon as the box is closed (the thread sleeps 50 ms first, so
	// the take is most likely waiting; if not, a closed box answers at once all the same).
	std::atomic<bool> returned{ false };
	Clock::time_point start = Clock::now();
	auto waiter = std::async(std::launch::async, [&] {
		std::optional<int> v = box.take(std::chrono::milliseconds(10000));
		returned = true;
		return v;
	});
	std::this_thread::sleep_for(std::chrono::milliseconds(50));
	CHECK_FALSE(returned);
	box.close();
	REQUIRE(waiter.wait_for(std::chrono::seconds(2)) == std::future_status::ready);
	CHECK_FALSE(waiter.get().has_value());
	CHECK(seconds_since(start) < 2.0);
	// Closed: takes return at once.
	start = Clock::now();
	CHECK_FALSE(box.take(std::chrono::milliseconds(5000)).has_value());
	CHECK(seconds_since(start) < 1.0);

	// A waiting take also wakes on put.
	box.reopen();
	CHECK(box.dropped_count() == 0);
	CHECK(box.put_count() == 0);
	auto taker = std::async(std::launch::async, [&] { return box.take(std::chrono::milliseconds(10000)); });
	std::this_thread::sleep_for(std::chrono::milliseconds(20));
	box.put(7);
	REQUIRE(taker.wait_for(std::chrono::seconds(2)) == std::future_status::ready);
	const std::optional<int> seven = taker.get();
	REQUIRE(seven.has_value());
	CHECK(*seven == 7);
	CHECK(box.dropped_count() == 0);
}

TEST_CASE("engine: a probe's map raycasts dense_faces_per_render faces and keeps the others until their turn") {
	const Recording &rec = recording();
	LiveRoomConfig cfg = live_config(rec);
	cfg.dense_faces_per_render = 2;
	LiveRoom engine;
	REQUIRE(engine.configure(cfg) == "");
	const size_t split = rec.events.size() / 2;
	for (size_t i = 0; i < split; i++) {
		push_event(engine, rec, rec.events[i]);
	}
	const int probe = engine.add_probe(rec.probe, PROBE_SIZE);
	engine.render_probes(); // nothing kept yet: all six faces
	const auto face_diff = [](const Cubemap &p_a, const Cubemap &p_b, int p_face) {
		return cv::norm(p_a.faces[size_t(p_face)], p_b.faces[size_t(p_face)], cv::NORM_INF);
	};
	Cubemap full = engine.render_at(rec.probe, PROBE_SIZE);
	for (int f = 0; f < 6; f++) {
		CHECK(face_diff(engine.probe_map(probe)->cubemap, full, f) <= TEXEL_TOL);
	}
	for (size_t i = split; i < rec.events.size(); i++) {
		push_event(engine, rec, rec.events[i]);
	}
	engine.finish();
	full = engine.render_at(rec.probe, PROBE_SIZE);
	// The next map raycasts faces 2 and 3 (0 and 1 went first after the six); the others are the
	// model of half the recording.
	engine.render_probes();
	int stale = 0;
	for (int f = 0; f < 6; f++) {
		const double diff = face_diff(engine.probe_map(probe)->cubemap, full, f);
		if (f == 2 || f == 3) {
			CHECK(diff <= TEXEL_TOL);
		} else {
			stale += diff > TEXEL_TOL ? 1 : 0;
		}
	}
	CHECK(stale > 0); // the second half of the sweep changed what some kept face sees
	// Two more maps and every face has had its turn.
	engine.render_probes();
	engine.render_probes();
	for (int f = 0; f < 6; f++) {
		CHECK(face_diff(engine.probe_map(probe)->cubemap, full, f) <= TEXEL_TOL);
	}
	// A moved probe keeps nothing: its first map is whole.
	const glm::dvec3 moved = rec.probe + glm::dvec3(0.1, 0.0, 0.0);
	engine.set_probe(probe, moved, PROBE_SIZE);
	engine.render_probes();
	const Cubemap full_moved = engine.render_at(moved, PROBE_SIZE);
	for (int f = 0; f < 6; f++) {
		CHECK(face_diff(engine.probe_map(probe)->cubemap, full_moved, f) <= TEXEL_TOL);
	}
}

// ---------------------------------------------------------------- corrupt frames mid-stream (issue #17)

TEST_CASE("engine: corrupt frames in the middle of a stream are refused or lost and counted; tracking and the maps go on") {
	const Recording &rec = recording();
	LiveRoom engine;
	REQUIRE(engine.configure(live_config(rec)).empty());
	const int probe = engine.add_probe(rec.probe, PROBE_SIZE);
	const RgbdFrame &sample = rec.rgbd.front();
	// What a failing driver or a damaged file can hand over, each once, half-way through.
	std::vector<RgbdFrame> bad_rgbd(4, sample);
	bad_rgbd[0].rgb = cv::Mat(sample.rgb.rows / 2, sample.rgb.cols / 2, CV_8UC3, cv::Scalar(1, 2, 3)); // the wrong size
	bad_rgbd[1].rgb = cv::Mat();
	bad_rgbd[1].depth_m = cv::Mat(); // nothing at all
	bad_rgbd[2].depth_m = cv::Mat(sample.depth_m.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
	bad_rgbd[2].depth_m(cv::Rect(0, 0, 40, 40)).setTo(-3.0f); // infinite and negative depth
	bad_rgbd[3].depth_m = cv::Mat(sample.depth_m.size(), CV_16UC1, cv::Scalar(500)); // the raw type, not metres
	std::vector<FisheyeFrame> bad_fisheye(3, rec.fisheye.front());
	bad_fisheye[0].image = cv::Mat(17, 23, CV_8UC1, cv::Scalar(9)); // the wrong size
	bad_fisheye[1].image = cv::Mat(rec.fisheye.front().image.size(), CV_32FC3, cv::Scalar(std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f));
	bad_fisheye[1].hdr = true; // NaN radiance
	bad_fisheye[2].image = cv::Mat();

	size_t rgbd_seen = 0;
	for (const Event &event : rec.events) {
		if (!event.fisheye && rgbd_seen++ == RGBD_FRAMES / 2) {
			for (RgbdFrame bad : bad_rgbd) {
				bad.timestamp_s = rec.rgbd[event.index].timestamp_s - 0.004; // between two good frames
				engine.push_rgbd(bad);
			}
			for (FisheyeFrame bad : bad_fisheye) {
				bad.timestamp_s = rec.rgbd[event.index].timestamp_s - rec.rig.fisheye_time_offset_s - 0.002;
				engine.push_fisheye(bad);
			}
		}
		push_event(engine, rec, event);
	}
	engine.finish();
	engine.render_probes();
	const LiveRoomStats stats = engine.stats();
	MESSAGE("stage errors " << stats.stage_errors << ", lost " << stats.lost << "; last error: " << stats.last_error << "; fisheye pushed " << stats.fisheye_pushed << ", integrated " << stats.fisheye_integrated << ", without pose " << stats.fisheye_without_pose << " (" << rec.fisheye.size() << " good)");
	// Each bad RGB-D frame is lost (nothing fused from it); each bad fisheye frame is refused,
	// named, and never integrated (a wrong-sized one once textured the room silently).
	CHECK(stats.lost >= bad_rgbd.size());
	CHECK(stats.stage_errors == bad_fisheye.size());
	CHECK(stats.last_error.find("fisheye frame: an empty image") == 0);
	CHECK(stats.fisheye_integrated == rec.fisheye.size());
	// Tracking goes on: every good frame's pose as without the bad ones, to the tolerance that two
	// runs of the same frames keep (the bad frames fuse nothing, so the model is the same).
	const Trajectory &clean = step_result().trajectory;
	const Trajectory tracked = engine.trajectory();
	size_t compared = 0;
	for (const RgbdFrame &good : rec.rgbd) {
		Pose a, b;
		std::string error;
		if (clean.pose_at(good.timestamp_s, &a, &error) && tracked.pose_at(good.timestamp_s, &b, &error)) {
			CHECK(glm::length(a.translation - b.translation) < 1e-3);
			compared++;
		}
	}
	CHECK(compared + 2 >= rec.rgbd.size());
	// Nothing non-finite reached the coarse texture or the map.
	const auto snapshot = engine.coarse_snapshot();
	REQUIRE(snapshot != nullptr);
	CHECK(cv::checkRange(snapshot->atlas));
	const auto map = engine.probe_map(probe);
	REQUIRE(map != nullptr);
	for (const cv::Mat &face : map->cubemap.faces) {
		CHECK(cv::checkRange(face));
	}
}

// ---------------------------------------------------------------- the room replaced, turned and found (issue #18)

namespace {

// The whole recording through a step-mode engine with p_config.
void play_all(LiveRoom &p_engine, const Recording &p_rec, size_t p_from = 0, size_t p_to = SIZE_MAX) {
	for (size_t e = p_from; e < std::min(p_to, p_rec.events.size()); e++) {
		push_event(p_engine, p_rec, p_rec.events[e]);
	}
}

// The mean absolute difference between two maps of the same scene whose worlds differ by
// p_b_from_a's rotation: each is read along the same physical directions (bilinear).
double mean_turned_difference(const Cubemap &p_a, const Cubemap &p_b, const glm::dquat &p_b_from_a) {
	double sum = 0.0;
	int n = 0;
	for (int i = 0; i < 40; i++) {
		for (int j = 0; j < 80; j++) {
			const double theta = std::numbers::pi * (i + 0.5) / 40.0, phi = 2.0 * std::numbers::pi * (j + 0.5) / 80.0;
			const glm::dvec3 in_a(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
			const glm::dvec3 a = sample_cubemap(p_a, in_a), b = sample_cubemap(p_b, p_b_from_a * in_a);
			sum += std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z);
			n += 3;
		}
	}
	return sum / n;
}

} // namespace

TEST_CASE("engine: a room turned and moved in the world gives the same maps, read along the same directions") {
	// One world (A, the recording's) and the same world turned 30 degrees about a tilted axis and
	// moved (B): the room, the true poses and the probe all carried into B. The coarse model (true
	// poses, no dense model) must then see the same room from the same place.
	const Recording &rec = recording();
	LiveRoomConfig a = live_config(rec);
	a.dense = false;
	a.coarse_poses = PoseSource::GroundTruth;
	const synth_frames::LivingRoom &room = synth_frames::living_room();
	std::string error;
	for (int i = 0; i < RGBD_FRAMES; i++) {
		const double t = i / RGBD_RATE_HZ;
		REQUIRE(a.ground_truth.append({ t, room.trajectory.world_from_rgb(t) }, &error));
	}
	Pose b_from_a;
	b_from_a.rotation = glm::angleAxis(30.0 * std::numbers::pi / 180.0, glm::normalize(glm::dvec3(0.3, 1.0, -0.2)));
	b_from_a.translation = glm::dvec3(1.5, -0.4, 2.0);
	LiveRoomConfig b = a;
	b.world_from_room = b_from_a;
	b.initial_rgb_pose = compose(b_from_a, a.initial_rgb_pose);
	b.ground_truth.clear();
	for (const TimedPose &pose : a.ground_truth.get_samples()) {
		REQUIRE(b.ground_truth.append({ pose.t_s, compose(b_from_a, pose.world_from_camera) }, &error));
	}
	LiveRoom engine_a, engine_b;
	REQUIRE(engine_a.configure(a) == "");
	REQUIRE(engine_b.configure(b) == "");
	play_all(engine_a, rec);
	play_all(engine_b, rec);
	const Cubemap map_a = engine_a.render_at(rec.probe, 48);
	const Cubemap map_b = engine_b.render_at(transform_point(b_from_a, rec.probe), 48);
	const double level = mean_value(map_a);
	REQUIRE(level > 0.02);
	// The two read the same atlas along the same directions; only the texel grids differ (48^2
	// faces turned against each other): a few percent of the level at the room's edges.
	const double turned = mean_turned_difference(map_a, map_b, b_from_a.rotation);
	CHECK(turned < 0.05 * level);
	// Read without the turn, the maps disagree several times more: the check above can fail.
	CHECK(mean_turned_difference(map_a, map_b, glm::dquat(1.0, 0.0, 0.0, 0.0)) > 4.0 * turned);
	// The room's extent follows it too.
	CHECK(engine_b.distance_outside_room_m(transform_point(b_from_a, rec.probe)) == 0.0);
	CHECK(engine_b.distance_outside_room_m(transform_point(b_from_a, glm::dvec3(-3.0, 1.0, -3.0))) > 1.0);
}

TEST_CASE("engine: set_room replaces the room and keeps the dense model, the tracking and the texture where the walls stayed") {
	const Recording &rec = recording();
	LiveRoom engine;
	REQUIRE(engine.configure(live_config(rec)) == "");
	const size_t half = rec.events.size() / 2;
	play_all(engine, rec, 0, half);
	const Trajectory before = engine.trajectory();
	const size_t fused_before = engine.slam_model()->integrated_count();
	const std::shared_ptr<const CoarseSnapshot> observed = engine.coarse_snapshot();
	REQUIRE(observed != nullptr);
	REQUIRE(fused_before > 0);

	// What the fisheye and the RGB camera observed, and its share of the room's surface texels.
	const CoarseTexture &before_texture = engine.coarse_model()->texture();
	const cv::Mat observed_before = before_texture.observed.clone();
	const cv::Mat seen_before = (before_texture.observed != 0) | (before_texture.rgb_quality > 0.0f);
	size_t surface_texels = 0;
	for (int y = 0; y < seen_before.rows; y++) {
		for (int x = 0; x < seen_before.cols; x++) {
			Vec3 point, normal;
			surface_texels += texel_to_world(engine.coarse_model()->mesh(), x, y, &point, &normal) ? 1 : 0;
		}
	}
	const double seen_share = double(cv::countNonZero(seen_before)) / double(surface_texels);
	REQUIRE(seen_share > 0.05);
	// The observed texels on the wall from p_a to p_b (either way round), -1 when no wall runs there.
	auto observed_on = [](const RoomMesh &p_mesh, const cv::Mat &p_observed, const glm::dvec2 &p_a, const glm::dvec2 &p_b) {
		for (const Chart &c : p_mesh.charts) {
			if (c.kind != SurfaceKind::Wall) {
				continue;
			}
			const Vec2 &ca = p_mesh.floorplan.points[size_t(c.wall_index)];
			const Vec2 &cb = p_mesh.floorplan.points[(size_t(c.wall_index) + 1) % p_mesh.floorplan.points.size()];
			const bool same = (glm::length(glm::dvec2(ca.x, ca.y) - p_a) < 1e-6 && glm::length(glm::dvec2(cb.x, cb.y) - p_b) < 1e-6) ||
					(glm::length(glm::dvec2(ca.x, ca.y) - p_b) < 1e-6 && glm::length(glm::dvec2(cb.x, cb.y) - p_a) < 1e-6);
			if (same) {
				return cv::countNonZero(p_observed(cv::Rect(c.x, c.y, c.w, c.h)));
			}
		}
		return -1;
	};
	REQUIRE(rec.floorplan.points.size() >= 4);
	const glm::dvec2 c2(rec.floorplan.points[2].x, rec.floorplan.points[2].y), c3(rec.floorplan.points[3].x, rec.floorplan.points[3].y);
	const int opposite_before = observed_on(engine.coarse_model()->mesh(), observed_before, c2, c3);

	SUBCASE("the same room again: every observation carries over, nothing else changes") {
		double carried = 0.0;
		REQUIRE(engine.set_room(true, rec.floorplan, Pose(), 0.0, 0.05, &carried) == "");
		CHECK(carried == doctest::Approx(seen_share).epsilon(1e-9));
		const std::shared_ptr<const CoarseSnapshot> kept = engine.coarse_snapshot();
		REQUIRE(kept != nullptr);
		// Texel for texel: the same observed mask, and where the fisheye observed, the old colour
		// exactly (the completed texture keeps observed colours; the fill comes back at the next
		// fisheye frame).
		const cv::Mat &seen = engine.coarse_model()->texture().observed;
		CHECK(cv::countNonZero(seen != observed_before) == 0);
		cv::Mat diff, per_texel;
		cv::absdiff(kept->atlas, observed->atlas, diff);
		cv::transform(diff, per_texel, cv::Matx13f(1.0f, 1.0f, 1.0f));
		double worst_seen = 0.0;
		cv::minMaxLoc(per_texel, nullptr, &worst_seen, nullptr, nullptr, seen);
		CHECK(worst_seen == 0.0);
		CHECK(engine.coarse_model()->frame_count() == observed->frames);
	}
	SUBCASE("the same room in the world, given in another frame: the floorplan turned -90 degrees and moved, the pose the opposite") {
		// room' = T^-1 room, world_from_room' = T: every surface stays where it was in the world.
		Pose t;
		t.rotation = glm::angleAxis(std::numbers::pi / 2.0, glm::dvec3(0.0, 1.0, 0.0));
		t.translation = glm::dvec3(0.7, 0.0, -1.3);
		const Pose t_inv = inverse(t);
		Floorplan turned = rec.floorplan;
		for (Vec2 &p : turned.points) {
			const glm::dvec3 q = transform_point(t_inv, glm::dvec3(p.x, 0.0, p.y));
			p = { q.x, q.z };
		}
		double carried = 0.0;
		REQUIRE(engine.set_room(true, turned, t, 0.0, 0.05, &carried) == "");
		// Another atlas layout samples the same observations: the share seen within a texel's
		// rounding at the charts' borders (2 texels of 5 cm on walls a few metres long: 4 %).
		CHECK(carried == doctest::Approx(seen_share).epsilon(0.04));
		CHECK(engine.coarse_model()->frame_count() == observed->frames);
	}
	SUBCASE("one wall moved 1 m out: its texels are observed anew, the walls that stayed carry over exactly") {
		Floorplan moved = rec.floorplan;
		// The edge from points[0] to points[1] pushed out along its outward normal.
		const Vec2 a = moved.points[0], b = moved.points[1];
		const glm::dvec2 along = glm::normalize(glm::dvec2(b.x - a.x, b.y - a.y));
		glm::dvec2 out(along.y, -along.x);
		const double sign = floorplan_signed_area_m2(moved) > 0.0 ? 1.0 : -1.0; // counter-clockwise: the outside is to the right
		out *= sign;
		moved.points[0] = { a.x + out.x, a.y + out.y };
		moved.points[1] = { b.x + out.x, b.y + out.y };
		double carried = 0.0;
		REQUIRE(engine.set_room(true, moved, Pose(), 0.0, 0.05, &carried) == "");
		CHECK(carried > 0.0);
		CHECK(carried < seen_share);
		// Per wall: the moved one (its line is 1 m from the old, beyond the 5 cm) takes nothing; a
		// wall neither moved nor lengthened (not next to it) keeps every observed texel.
		const RoomMesh &mesh = engine.coarse_model()->mesh();
		const cv::Mat &now_seen = engine.coarse_model()->texture().observed;
		const glm::dvec2 moved_a(moved.points[0].x, moved.points[0].y), moved_b(moved.points[1].x, moved.points[1].y);
		CHECK(observed_on(mesh, now_seen, moved_a, moved_b) == 0);
		// The wall from corner 2 to 3 touches neither moved corner: all it had, it keeps.
		CHECK(opposite_before >= 0);
		CHECK(observed_on(mesh, now_seen, c2, c3) == opposite_before);
	}
	SUBCASE("an invalid room is refused and the old one stays") {
		Floorplan broken;
		broken.points = { { 0.0, 0.0 }, { 1.0, 0.0 } };
		broken.ceiling_height_m = 2.5;
		CHECK_FALSE(engine.set_room(true, broken, Pose()).empty());
		// Nothing half-replaced: the old texture is still there.
		CHECK(engine.coarse_model()->frame_count() == observed->frames);
		REQUIRE(engine.room_mesh() != nullptr);
		CHECK(engine.room_mesh()->floorplan.points.size() == rec.floorplan.points.size());
		Pose nan_pose;
		nan_pose.translation.x = std::numeric_limits<double>::quiet_NaN();
		CHECK(engine.set_room(true, rec.floorplan, nan_pose) == "the room's pose is not finite");
	}
	// Whatever the room did, SLAM went on from where it was: the trajectory so far is unchanged and
	// the rest of the recording is tracked and fused.
	check_same_trajectory(engine.trajectory(), before, 0.0, 0.0);
	CHECK(engine.slam_model()->integrated_count() == fused_before);
	play_all(engine, rec, half);
	CHECK(engine.slam_model()->integrated_count() > fused_before);
	CHECK(engine.stats().lost == 0);
	CHECK(engine.coarse_snapshot() != nullptr);
}

TEST_CASE("engine: the room is found from the sweep in step mode and by the room worker; its fisheye views stay spread") {
	const Recording &rec = recording();
	LiveRoomConfig cfg = live_config(rec);
	cfg.has_room = false;
	cfg.find_room = true;
	cfg.find_room_views = 2; // thinned after 4 kept: 7 fisheye frames over 0.6 s
	cfg.find_room_interval_s = 0.05;
	SUBCASE("step mode: find_room_now") {
		LiveRoom engine;
		REQUIRE(engine.configure(cfg) == "");
		CHECK(engine.found_room() == nullptr);
		play_all(engine, rec);
		const std::shared_ptr<const FoundRoom> found = engine.find_room_now();
		REQUIRE(found != nullptr);
		CHECK(found->version == 1);
		CHECK(engine.found_room() == found);
		CHECK(found->fused_frames == size_t(RGBD_FRAMES));
		CHECK(found->samples.size() > 1000);
		// Kept: at most 2 * find_room_views - 1, spread: the first frame and a later one.
		CHECK(found->fisheye_views >= 2);
		CHECK(found->fisheye_views < 4);
		// 0.6 s of a living room (one wall in view) is not a room: a clear state and a sentence.
		CHECK_FALSE(found->result.has_room);
		CHECK(found->result.estimate.state == RoomEstimateState::TooFewWalls);
		CHECK_FALSE(found->result.estimate.message.empty());
		CHECK(engine.find_room_now()->version == 2);
	}
	SUBCASE("threaded: the room worker publishes an estimate") {
		cfg.mesh_interval_frames = 5;
		LiveRoom engine;
		REQUIRE(engine.configure(cfg) == "");
		REQUIRE(engine.start());
		size_t rgbd = 0;
		for (const Event &event : rec.events) {
			push_event(engine, rec, event);
			if (!event.fisheye) { // paced: every RGB-D frame fused (the mailbox keeps only the newest)
				rgbd++;
				REQUIRE(wait_until([&] { return engine.stats().rgbd_processed >= rgbd; }, 30.0));
			}
		}
		CHECK(wait_until([&] { return engine.found_room() != nullptr; }, 120.0));
		CHECK(engine.found_room()->fisheye_views >= 2);
		engine.stop();
		CHECK(engine.stats().stage_errors == 0);
	}
	SUBCASE("without dense SLAM there is nothing to find it in") {
		cfg.dense = false;
		cfg.has_room = true; // something to model
		cfg.coarse_poses = PoseSource::GroundTruth;
		const synth_frames::LivingRoom &room = synth_frames::living_room();
		std::string error;
		REQUIRE(cfg.ground_truth.append({ 0.0, room.trajectory.world_from_rgb(0.0) }, &error));
		LiveRoom engine;
		REQUIRE(engine.configure(cfg) == "");
		const std::shared_ptr<const FoundRoom> found = engine.find_room_now();
		CHECK_FALSE(found->result.has_room);
		CHECK(found->result.estimate.message == "no dense model: finding the room needs dense SLAM");
	}
}
