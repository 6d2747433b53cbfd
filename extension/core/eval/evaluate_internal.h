#pragma once
// What evaluate*.cpp share and nothing else includes: RecordingEvaluation, evaluate_recording's
// steps (evaluate.cpp reads, configures, feeds and finishes; evaluate_cubemap.cpp renders and
// scores each cubemap), and the per-class, direction and geometry scoring and the oracles that it
// calls (evaluate_classes.cpp).

#include "evaluate.h"

#include <engine/live_room.h>
#include <envmap/baseline.h>
#include <recording/recording_reader.h>
#include <rig/photometry.h>
#include <source/recording_player.h>
#include <synth/synth_renderer.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace roomprobe::evaluate_detail {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

// The stems of the maps written into EvaluationOptions::out, in EvaluationVariant order.
inline constexpr const char *MAP_FILES[VARIANT_COUNT] = { "baseline", "coarse", "coarse_inpaint", "coarse_light_additive", "coarse_light_gain", "dense_true_poses",
	"dense_slam", "oracle_coarse_texture", "oracle_dense" };
inline constexpr const char *TRUTH_FILE = "ground_truth";

// Faces resized to p_size x p_size (area-averaged down, bilinear up).
Cubemap to_cubemap(const CubemapFaces &p_faces, int p_size);
// The same for a rendered map, its distances kept (nearest: no distance between two surfaces).
Cubemap to_cubemap(const Cubemap &p_map, int p_size);

// Where the dense pass painted the live map: the pixels it changed from the coarse render
// (CV_8UC1 faces, 255 there).
using FaceMasks = std::array<cv::Mat, 6>;
FaceMasks dense_coverage(const Cubemap &p_live, const Cubemap &p_coarse_only);

// The live engine's map split by DirectionClass (see evaluate.h): the fisheye's observed and
// saturated masks rendered as an atlas from the probe, and the pixels the dense pass changed.
void split_by_direction(const LiveRoom &p_engine, const CoarseCubemapRenderer &p_renderer, const Cubemap &p_with_dense, const FaceMasks &p_dense,
		const Cubemap &p_truth, const glm::dvec3 &p_probe, int p_render_size, DirectionClassScores r_scores[DIRECTION_CLASS_COUNT]);

// The live map split by GeometryClass (see evaluate.h): p_prism from prism_directions, p_dense
// from dense_coverage.
void split_by_geometry(const Cubemap &p_with_dense, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism,
		DirectionClassScores r_scores[GEOMETRY_CLASS_COUNT]);

// The oracles of the two models (see EvaluationVariant): the live map with the truth put in where
// the oracle's model would have shown it. p_prism: prism_directions at the scored size.
void compose_oracles(const Cubemap &p_live, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism, Cubemap *r_coarse_oracle,
		Cubemap *r_dense_oracle);

// EvaluationResult::mirrors at one cubemap: mirror spheres of MIRROR_RADII_M at the probe, read
// from the true map (p_truth with the scene's own distances) and from p_live; a radius that would
// reach into the scene is left out.
void measure_mirrors(const synth::SynthRenderer &p_scene, const Cubemap &p_truth, const Cubemap &p_live, const glm::dvec3 &p_probe, double p_time_s,
		EvaluationResult *r_result);

// The SLAM variant's figures: tracking states, timings and ATE of the tracked engine.
class SlamFigures {
public:
	void add(const TrackedFrame &p_frame, const Trajectory &p_truth, SlamScores *r_scores) {
		r_scores->frames++;
		r_scores->good += p_frame.state == TrackingState::Good ? 1 : 0;
		r_scores->poor += p_frame.state == TrackingState::Poor ? 1 : 0;
		r_scores->lost += p_frame.state == TrackingState::Lost ? 1 : 0;
		r_scores->track_ms += p_frame.timings.track_ms;
		r_scores->integrate_ms += p_frame.timings.integrate_ms;
		r_scores->raycast_ms += p_frame.timings.raycast_ms;
		Pose truth;
		std::string error;
		if (p_frame.state == TrackingState::Lost || !p_frame.has_pose || !p_truth.pose_at(p_frame.timestamp_s, &truth, &error)) {
			return;
		}
		const double e = glm::length(p_frame.world_from_camera.translation - truth.translation);
		ate_sum_sq += e * e;
		ate_count++;
		r_scores->ate_max_m = std::max(r_scores->ate_max_m, e);
	}
	void add_render(double p_ms) {
		render_ms += p_ms;
		renders++;
	}
	void finish(SlamScores *r_scores) const {
		const double n = r_scores->frames > 0 ? double(r_scores->frames) : 1.0;
		r_scores->track_ms /= n;
		r_scores->integrate_ms /= n;
		r_scores->raycast_ms /= n;
		r_scores->ate_rmse_m = ate_count > 0 ? std::sqrt(ate_sum_sq / double(ate_count)) : 0.0;
		r_scores->dense_render_ms = renders > 0 ? render_ms / double(renders) : 0.0;
	}

private:
	double ate_sum_sq = 0.0;
	size_t ate_count = 0;
	double render_ms = 0.0;
	size_t renders = 0;
};

// The frames of one stream that were skipped: how many, and why the first was.
struct SkippedFrames {
	size_t count = 0;
	std::string first;

	void add(const std::string &p_why) {
		if (count++ == 0) {
			first = p_why;
		}
	}
	// Why none was used: "3 skipped; the first: WHY", or, with none skipped, that none came in time.
	std::string describe(double p_last_cubemap_s) const {
		if (count == 0) {
			char text[160];
			std::snprintf(text, sizeof(text), "none is stamped at or before the last ground-truth cubemap scored (%.3f s)", p_last_cubemap_s);
			return text;
		}
		return std::to_string(count) + " skipped; the first: " + first;
	}
};

// One evaluate_recording: its steps over the engines and running figures they share, in the order
// run() takes them (each cubemap's in evaluate_cubemap.cpp, the rest in evaluate.cpp). A step that
// fails sets result.error and returns false.
class RecordingEvaluation {
public:
	explicit RecordingEvaluation(const EvaluationOptions &p_options) :
			options(p_options) {}

	void run();
	EvaluationResult take_result() { return std::move(result); }

private:
	using Estimates = Cubemap[VARIANT_COUNT];

	void say(const std::string &p_line) const;
	const RecordingReader &reader() const { return player.reader(); }
	bool open_recording();
	bool read_light_switch();
	bool build_base_config();
	bool configure_engines();
	void load_oracles();
	bool start_scoring();
	void feed_until(double p_time_s);
	void feed_fisheye(size_t p_event);
	void evaluate_cubemap(size_t p_index);
	void render_variants(const glm::dvec3 &p_probe, Estimates &r_estimates);
	void render_dense(size_t p_index, double p_time_s, const Cubemap &p_truth, const glm::dvec3 &p_probe, Estimates &r_estimates);
	const FaceMasks &dense_covers(const Cubemap &p_live, const glm::dvec3 &p_probe, FaceMasks *io_covers);
	bool splits_at(size_t p_index, double p_time_s) const;
	void score_variants(double p_time_s, const Cubemap &p_truth, const Estimates &p_estimates);
	void write_maps(const Estimates &p_estimates, const Cubemap &p_truth);
	bool finish();

	const EvaluationOptions &options;
	// options.no_fisheye, or the recording's rig has none (open_recording).
	bool no_fisheye = false;
	EvaluationResult result;
	RecordingPlayer player;
	// The variants, each one LiveRoom in step mode, as the nodes and the benchmark run it: (b, c)
	// share one engine (raw and completed texture), (e, f) another (without and with its dense
	// model fused at the true poses), and (g) is the live system on tracked poses.
	LiveRoomConfig base, no_light, additive, gain, tracked;
	LiveRoom engine_plain, engine_additive, engine_gain, engine_tracked;
	std::vector<std::pair<LiveRoom *, const LiveRoomConfig *>> engines;
	FisheyeLinearizer linearizer; // the baseline sees the frames as the engines do
	std::optional<BaselineEnvmap> baseline;
	// The oracles need the true scene (and the dense variants they start from).
	std::unique_ptr<synth::SynthRenderer> truth_scene;
	int variant_count = 0;
	FaceMasks prism_mask; // prism_directions at the scored size, for prism_mask_at
	glm::dvec3 prism_mask_at = glm::dvec3(std::numeric_limits<double>::quiet_NaN());
	SlamFigures slam_figures;
	double render_ms[3] = { 0.0, 0.0, 0.0 }; // coarse renders of (c), (d), (e), summed
	GroundTruthCubemapResult first;
	int size = 0, render_size = 0; // render_size: the maps, area-averaged down to size to be scored
	size_t count = 0; // the cubemaps to score
	double baseline_total_ms = 0.0, metrics_total_ms = 0.0;
	size_t rgbd_frames_used = 0, comparisons = 0;
	SkippedFrames fisheye_skipped, rgbd_skipped, cubemaps_skipped; // why, for an error that says so by itself
};

} // namespace roomprobe::evaluate_detail
