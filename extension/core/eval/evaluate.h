#pragma once
// Evaluating environment-map estimates against a recording's ground-truth cubemaps (paper §5.3).
//
// For every ground-truth cubemap (one per fisheye frame in the synthetic recordings, RGB-D clock),
// every frame up to that instant is fed, in time order (the recording's playback events), to the
// variants. All but the baseline are the live system itself, engine/live_room.h in step mode:
//   baseline        §5.3's baseline (envmap/baseline.h), rotation only, at the true poses;
//   coarse          the coarse model at true poses, no inpainting, no lighting compensation;
//   coarse+inpaint  the same engine's completed texture (§4.5);
//   +light(add)     inpainting and §4.6's additive model (ADDITIVE_PAPER);
//   +light(gain)    inpainting and the robust per-channel gain (GAIN_ROBUST);
//   +dense (true)   the same engine with its dense model over the map (§4.7), the RGB-D frames
//                   fused at their ground-truth poses (DenseSlam::process_at_pose);
//   +dense (SLAM)   the live system: the RGB-D camera tracked from the room's initial pose, the
//                   fisheye's poses from that tracked trajectory, the dense model over it; its
//                   ATE is reported;
//   oracle: true coarse texture, oracle: true dense model   the live map with the truth put in
//                   where that model would show it (EvaluationVariant below; with the true scene);
// each rendered at the cubemap's probe (LiveRoom::render_at) and compared with eval/metrics.h.
//
// Photometric units: the ground truth is linear radiance. A synthetic recording's synth.yaml gives
// the rig's photometry (rig/photometry.h: read_recording_photometry), which the engines apply to
// every frame as the nodes do: fisheye frames sRGB-decoded, over the exposure and the vignetting,
// i.e. a perfect photometric calibration; the dense model's 8-bit colours sRGB-decoded over the
// RGB camera's exposure when drawn. Without synth.yaml (or with linearise off) the frames are used
// as they are (8-bit value / 255, the coarse texture's convention).
//
// Light switch (living_room): synth.yaml's light_switch_s (RGB-D clock; -1: none). The §4.6
// effect is measured on the CUBEMAPS: mean PSNR / SSIM over the frames after the switch (the
// true texture of not-yet-re-observed texels is not available from a recording).

#include "metrics.h"
#include "mirror_error.h"

#include <envmap/cubemap.h>
#include <gpu/compute_device.h>
#include <pipeline/coarse_pipeline.h>

#include <functional>
#include <string>
#include <vector>

namespace roomprobe {

struct EvaluationOptions {
	std::string recording; // folder
	std::string out; // empty: write nothing; else the last frame's cubemaps (EXR + PNG net) per variant
	int cubemap_size = 0; // 0: the ground truth's face size; else both are compared at this size
	double texel_size_m = 0.02;
	bool linearise = true; // as described above, when synth.yaml is present
	size_t max_cubemaps = 0; // 0: all
	bool dense = true; // the two dense variants (they run SLAM on every RGB-D frame: slower)
	int render_scale = 1; // maps rendered at render_scale x cubemap_size, area-averaged down to be scored
	bool rgb_texture = false; // the coarse model also textured from the RGB camera (coarse/rgb_texture_update.h)
	// The rig as an RGB-D camera alone (issue #43): the engines' rig has no fisheye, they get no
	// fisheye frames but every RGB-D frame, and the coarse model is textured from the RGB camera
	// (CoarsePipeline::add_rgb_view). The baseline (5.3) keeps the fisheye; the ground truth is
	// the same, so the two runs compare the same sweep with and without the fisheye.
	bool no_fisheye = false;
	// > 0: the dense model's reach, metres: depth readings fused up to this far (TsdfOptions'
	// max_depth_m) and the dense pass drawn this far from the probe (LiveRoomConfig's
	// dense_render_far_m); 0: their defaults (4 m).
	double dense_range_m = 0.0;
	// > 0: the dense pass raycasts at 1 / dense_scale of the face size (LiveRoomConfig::
	// dense_render_scale; issue #42's silhouettes); 0: the engine's default (2).
	int dense_scale = 0;
	// > 0: the gain variants' lighting change is a gain field with this prior on its slope (log
	// gain per metre; LightingOptions::field_prior_per_m, issue #42); 0: one gain.
	double lighting_field_prior_per_m = 0.0;
	bool oracles = true; // the oracle variants, when the recording's true scene can be rebuilt
	// Non-empty: the coarse model uses this room file (a room found from the sweep by roomprobe_room,
	// issue #18) instead of the recording's true room. It is placed in the recording's world by
	// the two rooms' initial_rgb_pose (both are the first RGB-D frame's camera), so the maps are
	// scored at the same probes against the same truth.
	std::string room_file;
	// Where the live variants' kernels with a GPU twin run (LiveRoomConfig::compute_backend);
	// EvaluationResult::compute says where they ran.
	ComputeBackend compute_backend = ComputeBackend::Cpu;
	std::function<void(const std::string &)> progress; // optional
};

struct FrameScore {
	double timestamp_s = 0.0; // RGB-D clock
	CubemapMetrics metrics;
};

// The moments of the sweep that the report gives besides the means: a user cares about the map
// after a short sweep, not the average from the start.
inline constexpr double SWEEP_MOMENTS_S[3] = { 2.0, 5.0, 10.0 };

// The mirror spheres' radii (EvaluationResult::mirrors): an ornament and a ball on the table (the
// synthetic probes sit 15 cm over it). A radius that would reach the scene is left out.
inline constexpr double MIRROR_RADII_M[2] = { 0.05, 0.12 };

struct VariantScores {
	std::string name;
	std::vector<FrameScore> frames;
	// The last frame at or before each of SWEEP_MOMENTS_S after the recording's first frame; -1
	// when the recording is shorter.
	int at_moment[3] = { -1, -1, -1 };
	double mean_psnr_mu_db = 0.0, mean_psnr_worst5_db = 0.0;
	double mean_psnr_db = 0.0, mean_ssim = 0.0, mean_psnr_linear_db = 0.0, mean_ssim_linear = 0.0;
	double mean_irradiance_error = 0.0; // CubemapMetrics::irradiance_error's mean
	size_t after_switch_frames = 0;
	double after_switch_psnr_db = 0.0, after_switch_ssim = 0.0; // 0 frames: 0
	double after_switch_psnr_linear_db = 0.0, after_switch_irradiance_error = 0.0;
	Cubemap last; // the estimate of the last frame
};

enum EvaluationVariant {
	VARIANT_BASELINE = 0,
	VARIANT_COARSE,
	VARIANT_INPAINT,
	VARIANT_LIGHT_ADDITIVE,
	VARIANT_LIGHT_GAIN,
	VARIANT_DENSE_TRUE_POSES,
	VARIANT_DENSE_SLAM,
	// The budget's oracles of the two models (with the dense variants, on a recording whose true
	// scene is known: eval/truth_scene.h), applied to +dense (SLAM)'s map direction by direction:
	//   true coarse texture: every direction whose first true surface lies on the room's prism and
	//     that the dense model does not cover shows the truth (a perfect texture seen from the
	//     probe); the rest as the live map;
	//   true dense model: every direction whose first true surface is not the prism (what stands
	//     in the room) shows the truth; the rest as the live map.
	VARIANT_ORACLE_COARSE_TEXTURE,
	VARIANT_ORACLE_DENSE,
	VARIANT_COUNT
};

// The tracked RGB-D trajectory of the SLAM variant against the ground truth.
struct SlamScores {
	size_t frames = 0, good = 0, poor = 0, lost = 0;
	double ate_rmse_m = 0.0; // over the frames with a pose (good or poor), same timestamps, no alignment
	double ate_max_m = 0.0;
	double track_ms = 0.0, integrate_ms = 0.0, raycast_ms = 0.0; // means per RGB-D frame
	double dense_render_ms = 0.0; // the dense pass of one cubemap, mean
};

// Where the live system's map comes from, direction by direction (the budget's split): the room
// texel the direction sees was observed by the fisheye (and held a clipped value: saturated), or
// only the RGB-D camera saw it (the dense model covers it, or the texel holds an RGB value), or
// neither saw it (inpainted).
enum DirectionClass {
	DIRECTIONS_FISHEYE = 0,
	DIRECTIONS_SATURATED,
	DIRECTIONS_RGBD_ONLY,
	DIRECTIONS_NEVER_SEEN,
	DIRECTION_CLASS_COUNT
};

// The same map split by what each direction truly sees (the true scene's first surface on the
// room's prism or not, eval/truth_scene.h) and what the live map shows there (the dense model
// painted it or not): where each model's error lies.
enum GeometryClass {
	GEOMETRY_PRISM_COARSE = 0, // the room's shell, shown by the coarse model
	GEOMETRY_PRISM_DENSE, // the room's shell, shown by the dense model
	GEOMETRY_CONTENTS_DENSE, // what stands in the room, shown by the dense model
	GEOMETRY_CONTENTS_COARSE, // what stands in the room, shown by the coarse model (onto the prism)
	GEOMETRY_CLASS_COUNT
};

struct DirectionClassScores {
	double share = 0.0; // of the map's pixels
	double psnr_db = 0.0; // tone-mapped, over those pixels (PSNR_CAP_DB when none differ; 0 when there are none)
};

struct EvaluationResult {
	bool ok = false;
	std::string error;
	// With EvaluationOptions::out: "" when every map was written there, else what could not be
	// (naming the file and the system's reason); the scores stand either way (issue #38: a read-only
	// --out with --quiet ended with status 0 and nothing written).
	std::string out_error;
	// In EvaluationVariant order: all VARIANT_COUNT; up to DENSE_SLAM without the true scene;
	// up to LIGHT_GAIN without dense.
	std::vector<VariantScores> variants;
	std::string no_oracles; // why the oracle variants are missing (with dense); empty when present
	SlamScores slam; // with the dense variants
	// +dense (SLAM)'s map split by DirectionClass, at its last cubemap at or before 10 s into the
	// sweep (the last one of a shorter recording); with the dense variants.
	DirectionClassScores directions[DIRECTION_CLASS_COUNT];
	DirectionClassScores geometry[GEOMETRY_CLASS_COUNT]; // the same map by GeometryClass, with the true scene
	double directions_at_s = -1.0; // that cubemap's time, RGB-D clock; < 0: not measured
	// At the same cubemap, with the true scene: a mirror sphere at the probe against a ray-traced
	// reference (eval/mirror_error.h), read from the true map (the ground-truth cubemap and its true
	// distances) and from the live map (+dense (SLAM) and its distances), at MIRROR_RADII_M.
	struct MirrorRow {
		double radius_m = 0.0;
		bool true_map = false;
		MirrorScores scores;
	};
	std::vector<MirrorRow> mirrors;
	double mirror_clearance_m = 0.0; // the nearest true surface from that probe
	double light_switch_s = -1.0; // RGB-D clock; < 0: none
	double start_s = 0.0; // the recording's first frame (RGB-D clock): the sweep's moments count from it
	bool linearised = false;
	size_t fisheye_frames_used = 0;
	std::string compute; // where +dense (SLAM)'s kernels ran (LiveRoomStats::compute), with the dense variants
	size_t cubemaps = 0;
	int cubemap_size = 0;
	// Per-frame averages, ms: the no-lighting pipeline (b/c), the additive (d) and gain (e) ones.
	CoarsePipelineTimings timings_inpaint, timings_additive, timings_gain;
	double baseline_ms = 0.0; // BaselineEnvmap::add_frame, per frame
	double metrics_ms = 0.0; // compare_cubemaps, per comparison
};

EvaluationResult evaluate_recording(const EvaluationOptions &p_options);
// The names of the files evaluate_recording may write into EvaluationOptions::out, each variant's
// last maps and the ground truth's as NAME.exr and NAME.png (roomprobe_eval keeps existing ones
// unless --force).
std::vector<std::string> evaluation_output_files();

// The error budget (issue #16): the live system, then rows with one stage replaced by its oracle
// (true poses; texels and maps at twice the resolution) or left out (the dense model; inpainting
// and lighting; the photometric calibration: the evaluation's own photometry is the synthetic
// truth, a perfect calibration), and with the RGB camera's texturing of the coarse model added.
// Four evaluations of the recording.
struct BudgetRow {
	std::string what;
	VariantScores scores;
};

struct BudgetResult {
	bool ok = false;
	std::string error;
	std::vector<BudgetRow> rows;
	std::vector<std::string> missing; // rows that could not be measured, each with why
	EvaluationResult shipped; // the first run's result (the live system as shipped): its direction split
	double start_s = 0.0;
	int cubemap_size = 0;
};

BudgetResult error_budget(const EvaluationOptions &p_options);
std::string format_budget(const BudgetResult &p_budget);

// The summary table (mean over the sequence, and after the switch when there is one), the
// per-stage timings and, with p_per_frame, one line per frame and variant.
std::string format_evaluation(const EvaluationResult &p_result, bool p_per_frame);

} // namespace roomprobe
