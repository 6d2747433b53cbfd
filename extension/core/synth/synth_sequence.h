#pragma once
// A synthetic recording: a hand-held trajectory of the rig in a synth Scene (round the table, or
// along a wall), RGB-D frames at one rate and fisheye frames at another on their own clock,
// ground-truth trajectories of both cameras, ground-truth cubemaps at the probe for every fisheye
// frame (recording/recording_writer.h, docs/recording-format.md), and checkerboard views of both
// cameras for calibration (calibration/ in the recording folder).

#include "synth_renderer.h"
#include "synth_scene.h"

#include <math/pose.h>
#include <recording/recording_writer.h>
#include <rig/rig.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace roomprobe::synth {

// ---------------------------------------------------------------- the hand-held trajectory

// A smooth (sums of sines), deterministic hand-held path, of the kind the scene asks for
// (Scene::trajectory). Defined for every t (also outside the recording), so the pose at any
// instant is exact.
//
// Orbit: round scene.look_target, radius about scene.orbit_radius_m, height about
// scene.camera_height_m with a sinusoidal bob, the RGB camera looking at the target with small
// yaw/pitch/roll jitter and tremor.
//
// WallSweep: facing the wall of scene.wall_sweep from about distance_m (+- 0.22 m, slowly: the
// hand moves forward and back), height about scene.camera_height_m, sweeping sideways along the
// wall from one end of [-half_length_m, half_length_m] about wall_point to the other and back
// (a cosine, at rest at the ends; one round trip in 9 to 11 s, drawn from the seed, as is which
// end it starts from), with hand-held yaw (+- 5 degrees), pitch (+- 3) and roll (+- 3) wander
// and tremor. The camera's view stays on the wall: the depth camera sees one plane.
//
// RoomSweep: carried along scene.room_sweep.path_xz (a cosine over the path's length: from the
// first point to the last in walk_s, at rest at both ends, then back), at about
// scene.camera_height_m, turning round at turn_rad_s (its sign from the seed) from a yaw drawn
// from the seed, pitched 5 to 28 degrees down (every 3.4 s: the floor, then the walls), with
// hand-held wander and tremor; with room.look_up_every_s, up to the ceiling now and then.
struct HandheldTrajectory {
	TrajectoryKind kind = TrajectoryKind::Orbit;
	glm::dvec3 target = glm::dvec3(0.0); // Orbit
	double radius_m = 1.5; // Orbit
	double height_m = 1.45;
	double start_angle_rad = 0.0; // Orbit
	double angular_speed_rad_s = 0.4; // Orbit; signed: the direction round the table
	WallSweepParams wall; // WallSweep
	double sweep_period_s = 10.0; // WallSweep: one round trip
	double sweep_sign = 1.0; // WallSweep: +1 starts at the -along end (along = up x normal), -1 at the other
	RoomSweepParams room; // RoomSweep
	std::array<double, 10> phases = {}; // of the wobbles, from the seed

	Pose world_from_rgb(double p_t_s) const; // t on the RGB-D clock

private:
	Pose room_sweep_pose(double p_t_s) const;
};

HandheldTrajectory make_handheld_trajectory(const Scene &p_scene, uint64_t p_seed);

// ---------------------------------------------------------------- the checkerboard target

struct CheckerboardSpec {
	// 10 x 7: one even and one odd count, so the pattern has no 180-degree symmetry and corner
	// detectors order the corners unambiguously.
	int squares_x = 10; // squares along the board's x; inner corners: squares_x - 1
	int squares_y = 7;
	double square_m = 0.035;
	double margin_m = 0.04; // white border around the squares
};

// The board frame: origin at the outer top-left corner of the squares (the first square is
// black), x along squares_x, y along squares_y, z = x cross y, on the side away from the printed
// face. Inner corner (i, j), 0 <= i < squares_x - 1, 0 <= j < squares_y - 1, is at
// ((i + 1) square_m, (j + 1) square_m, 0), listed row by row (i fastest), as
// cv::findChessboardCorners lists them for a board seen upright.
std::vector<glm::dvec3> checkerboard_corners(const CheckerboardSpec &p_board);

// A scene of the board alone at p_camera_from_board, seen from a camera at the origin, flat-lit,
// in front of a grey background.
Scene make_checkerboard_scene(const CheckerboardSpec &p_board, const Pose &p_camera_from_board);

// The fixed board poses (camera_from_board) the calibration views use.
std::vector<Pose> pinhole_board_poses(const CheckerboardSpec &p_board);
std::vector<Pose> fisheye_board_poses(const CheckerboardSpec &p_board);
// Boards both cameras see at once (rgb_from_board): ahead of the RGB camera and raised, near the
// upward fisheye's horizon. Their views calibrate rgb_from_fisheye and the depth.
std::vector<Pose> pair_board_poses(const CheckerboardSpec &p_board);

// ---------------------------------------------------------------- the recording

// How the fisheye's exposure changes from frame to frame (each frame's exposure is recorded in
// capture.txt, in microseconds: SYNTH_EXPOSURE_UNIT_US per unit of FisheyeOptions::exposure).
enum class ExposureMode {
	Fixed, // every frame at fisheye.exposure
	Auto, // a camera's auto-exposure: steers the mean code in the image circle towards auto_target_code, a frame late, damped
	Bracket, // cycles through bracket_ev stops about fisheye.exposure, frame by frame
};
inline constexpr double SYNTH_EXPOSURE_UNIT_US = 10000.0;
const char *exposure_mode_name(ExposureMode p_mode);

struct SequenceOptions {
	double duration_s = 10.0;
	uint64_t seed = 1;
	double rgbd_rate_hz = 30.0; // frame i at i / rate on the RGB-D clock
	double fisheye_rate_hz = 12.0; // frame k at k / rate on the fisheye's clock
	int cubemap_face_size = 128; // ground truth, every fisheye frame
	bool fisheye_hdr = false; // fisheye frames as linear EXR instead of 8-bit images
	bool calibration_views = true;
	int calibration_samples_per_axis = 4; // antialiasing of the board views (sub-pixel corners)
	RgbdOptions rgbd; // noise_seed is set per frame from seed
	FisheyeOptions fisheye; // its exposure is the reference (bracketing and auto-exposure scale it)
	ExposureMode exposure_mode = ExposureMode::Fixed;
	std::vector<double> bracket_ev = { -5.0, 0.0 }; // Bracket: stops (powers of 2) about the reference, in turn
	double auto_target_code = 110.0; // Auto: the mean 8-bit code it aims at
	bool photometric_views = true; // with calibration_views: an exposure sweep and a flat field (write_photometric_views)
	double cubemap_ldr_exposure = 1.0; // of the 8-bit view next to each cubemap EXR
	bool exr_full_float = false; // EXRs (cubemaps, HDR fisheye) as 32-bit float rather than half
	FrameFormat frame_format = FrameFormat::Zstd; // RGB, depth and 8-bit fisheye frames: raw frames (zstd) or PNG
	// The panorama the scene was made with (SceneOptions::panorama_path), written to synth.yaml as
	// scene_panorama ("none" when empty) so that the evaluation can rebuild the true scene
	// (eval/truth_scene.h).
	std::string scene_panorama_path;
	std::function<void(const std::string &)> progress; // optional: a line now and then
};

struct SequenceTimings {
	double scene_s = 0.0; // building the Embree scene
	double rgbd_s = 0.0; // rendering RGB-D frames
	double fisheye_s = 0.0; // rendering fisheye frames
	double cubemap_s = 0.0; // rendering ground-truth cubemaps
	double write_wait_s = 0.0; // waiting for the writer thread (encoding and writing files)
	double calibration_s = 0.0; // rendering and writing the checkerboard views
	double total_s = 0.0;
	size_t rgbd_frames = 0, fisheye_frames = 0, cubemaps = 0, calibration_views = 0;
};

struct SequenceResult {
	bool ok = false;
	std::string error; // names the file where one is involved
	SequenceTimings timings;
};

// The frame times of a recording of duration_s: RGB-D frames at i / rgbd_rate_hz in
// [0, duration_s); fisheye frames at k / fisheye_rate_hz on the fisheye's clock, those whose
// RGB-D-clock time (+ rig.fisheye_time_offset_s) falls within the RGB-D frames' span (so that
// fisheye_pose_at can interpolate them).
std::vector<double> rgbd_frame_times(const SequenceOptions &p_options);
std::vector<double> fisheye_frame_times(const SequenceOptions &p_options, double p_fisheye_time_offset_s);

// Renders and writes the whole recording into p_folder, which must not exist or be empty, and
// synth.yaml beside it: scene, seed, duration, rates, light_switch_s (-1: none) and the switched
// light's panel, the fisheye's vignetting and the exposures.
SequenceResult write_sequence(const std::string &p_folder, const Rig &p_rig, const Scene &p_scene, const SequenceOptions &p_options);

// Renders and writes the checkerboard views of both cameras into p_folder/calibration/:
// rgb/NNN.png, fisheye/NNN.png, for a rig with a fisheye pairs/NNN_rgb.png, NNN_fisheye.png and
// NNN_depth.png (both cameras at once, and the RGB-D camera's depth), and boards.yaml (the board,
// and per image its camera, pair, image, camera_from_board and the true pixel of every inner
// corner).
struct CalibrationResult {
	bool ok = false;
	std::string error;
	size_t views = 0;
};
// The fisheye's views are taken with p_fisheye's photometry (tone curve, gains, vignetting, its
// exposure: the reference).
// p_progress, when set, gets a line about every tenth of the views (the phase takes minutes).
CalibrationResult write_calibration_views(const std::string &p_folder, const Rig &p_rig, const CheckerboardSpec &p_board, int p_samples_per_axis,
		const FisheyeOptions &p_fisheye = FisheyeOptions(), const std::function<void(const std::string &)> &p_progress = {});

// The fisheye's photometric calibration views in p_folder/calibration/: an exposure sweep of the
// static scene from p_world_from_fisheye at time 0 (exposure/NNN.png, half stops from -4 to +4 about
// the reference), a flat field (flat_field.png: a uniform radiance over the lens, as through a
// diffuser) and photometric.yaml listing each image's exposure (microseconds) and the reference
// exposure at which the pairs' fisheye images were taken.
CalibrationResult write_photometric_views(const std::string &p_folder, const SynthRenderer &p_renderer, const OmniParams &p_fisheye,
		const Pose &p_world_from_fisheye, const FisheyeOptions &p_options);

} // namespace roomprobe::synth
