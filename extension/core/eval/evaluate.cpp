#include "evaluate.h"
#include "truth_scene.h"

#include <io/yaml_fields.h>

#include <engine/live_room.h>
#include <envmap/baseline.h>
#include <envmap/coarse_render.h>
#include <envmap/export.h>
#include <recording/recording_io.h>
#include <recording/recording_reader.h>
#include <recording/room_file.h>
#include <rig/fisheye_pose.h>
#include <rig/photometry.h>

#include <chrono>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>

namespace roomprobe {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

Cubemap to_cubemap(const CubemapFaces &p_faces, int p_size) {
	Cubemap map;
	map.size = p_size;
	for (int f = 0; f < 6; f++) {
		if (p_faces[f].cols == p_size) {
			map.faces[f] = p_faces[f];
		} else {
			cv::resize(p_faces[f], map.faces[f], cv::Size(p_size, p_size), 0, 0, p_faces[f].cols > p_size ? cv::INTER_AREA : cv::INTER_LINEAR);
		}
	}
	return map;
}

// The same for a rendered map, its distances kept (nearest: no distance between two surfaces).
Cubemap to_cubemap(const Cubemap &p_map, int p_size) {
	Cubemap map = to_cubemap(p_map.faces, p_size);
	if (has_distances(p_map)) {
		for (int f = 0; f < 6; f++) {
			if (p_map.size == p_size) {
				map.distance_m[size_t(f)] = p_map.distance_m[size_t(f)];
			} else {
				cv::resize(p_map.distance_m[size_t(f)], map.distance_m[size_t(f)], cv::Size(p_size, p_size), 0, 0, cv::INTER_NEAREST);
			}
		}
	}
	return map;
}

void add_timings(CoarsePipelineTimings *r_sum, const CoarsePipelineTimings &p_total, double p_scale) {
	r_sum->occlusion_ms = p_total.occlusion_ms * p_scale;
	r_sum->lighting_ms = p_total.lighting_ms * p_scale;
	r_sum->update_ms = p_total.update_ms * p_scale;
	r_sum->inpaint_ms = p_total.inpaint_ms * p_scale;
	r_sum->render_ms = p_total.render_ms * p_scale;
	r_sum->sh_ms = p_total.sh_ms * p_scale;
	r_sum->frame_ms = p_total.frame_ms * p_scale;
}

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

// Where the dense pass painted the live map: the pixels it changed from the coarse render
// (CV_8UC1 faces, 255 there).
using FaceMasks = std::array<cv::Mat, 6>;
FaceMasks dense_coverage(const Cubemap &p_live, const Cubemap &p_coarse_only) {
	FaceMasks covered;
	for (int f = 0; f < 6; f++) {
		cv::Mat difference, channels[3];
		cv::absdiff(p_live.faces[size_t(f)], p_coarse_only.faces[size_t(f)], difference);
		cv::split(difference, channels);
		covered[size_t(f)] = (channels[0] + channels[1] + channels[2]) > 0.0f; // any channel differs
	}
	return covered;
}

// The tone-mapped PSNR of p_estimate over each class of pixels that p_class(face, y, x) returns
// (0 .. p_count - 1), and each class's share of the map.
template <typename ClassOf>
void score_classes(const Cubemap &p_estimate, const Cubemap &p_truth, int p_count, DirectionClassScores *r_scores, ClassOf p_class) {
	std::vector<double> squared(size_t(p_count), 0.0), pixels(size_t(p_count), 0.0);
	const int size = p_truth.size;
	for (int f = 0; f < 6; f++) {
		const cv::Mat estimate = tone_map_face(p_estimate.faces[f]), truth = tone_map_face(p_truth.faces[f]);
		for (int y = 0; y < size; y++) {
			for (int x = 0; x < size; x++) {
				const size_t c = size_t(p_class(f, y, x));
				const cv::Vec3b e = estimate.at<cv::Vec3b>(y, x), t = truth.at<cv::Vec3b>(y, x);
				for (int k = 0; k < 3; k++) {
					squared[c] += (double(e[k]) - t[k]) * (double(e[k]) - t[k]);
				}
				pixels[c] += 1.0;
			}
		}
	}
	const double total = 6.0 * size * size;
	for (size_t c = 0; c < size_t(p_count); c++) {
		r_scores[c].share = pixels[c] / total;
		const double mse = pixels[c] > 0.0 ? squared[c] / (3.0 * pixels[c]) : 0.0;
		r_scores[c].psnr_db = pixels[c] == 0.0 ? 0.0 : (mse > 0.0 ? std::min(PSNR_CAP_DB, 10.0 * std::log10(255.0 * 255.0 / mse)) : PSNR_CAP_DB);
	}
}

// The live engine's map split by DirectionClass (see evaluate.h): the fisheye's observed and
// saturated masks rendered as an atlas from the probe, and the pixels the dense pass changed.
void split_by_direction(const LiveRoom &p_engine, const CoarseCubemapRenderer &p_renderer, const Cubemap &p_with_dense, const FaceMasks &p_dense,
		const Cubemap &p_truth, const glm::dvec3 &p_probe, int p_render_size, DirectionClassScores r_scores[DIRECTION_CLASS_COUNT]) {
	const CoarseTexture &texture = p_engine.coarse_model()->texture();
	cv::Mat masks(texture.color.size(), CV_32FC3, cv::Scalar::all(0.0));
	for (int y = 0; y < masks.rows; y++) {
		const float *fisheye_quality = texture.quality.ptr<float>(y); // > 0: a fisheye observation (an RGB one has 0)
		const uint8_t *saturated = texture.saturated.empty() ? nullptr : texture.saturated.ptr<uint8_t>(y);
		cv::Vec3f *out = masks.ptr<cv::Vec3f>(y);
		for (int x = 0; x < masks.cols; x++) {
			const bool rgb = !texture.rgb_quality.empty() && texture.rgb_quality.at<float>(y, x) > 0.0f;
			out[x] = cv::Vec3f(fisheye_quality[x] > 0.0f ? 1.0f : 0.0f, saturated && saturated[x] ? 1.0f : 0.0f, rgb ? 1.0f : 0.0f);
		}
	}
	const int size = p_truth.size;
	const Pose room_from_world = inverse(p_engine.config().world_from_room); // the coarse model's frame
	const Cubemap seen = to_cubemap(p_renderer.render(masks, transform_point(room_from_world, p_probe), p_render_size, room_from_world.rotation).faces, size);
	score_classes(p_with_dense, p_truth, DIRECTION_CLASS_COUNT, r_scores, [&](int p_face, int p_y, int p_x) {
		const cv::Vec3f mask = seen.faces[p_face].at<cv::Vec3f>(p_y, p_x);
		if (mask[0] > 0.5f) {
			return mask[1] > 0.5f ? int(DIRECTIONS_SATURATED) : int(DIRECTIONS_FISHEYE);
		}
		const bool dense = p_dense[size_t(p_face)].at<uint8_t>(p_y, p_x) != 0;
		return dense || mask[2] > 0.5f ? int(DIRECTIONS_RGBD_ONLY) : int(DIRECTIONS_NEVER_SEEN);
	});
}

// The live map split by GeometryClass (see evaluate.h): p_prism from prism_directions, p_dense
// from dense_coverage.
void split_by_geometry(const Cubemap &p_with_dense, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism,
		DirectionClassScores r_scores[GEOMETRY_CLASS_COUNT]) {
	score_classes(p_with_dense, p_truth, GEOMETRY_CLASS_COUNT, r_scores, [&](int p_face, int p_y, int p_x) {
		const bool dense = p_dense[size_t(p_face)].at<uint8_t>(p_y, p_x) != 0;
		if (p_prism[size_t(p_face)].at<uint8_t>(p_y, p_x)) {
			return dense ? int(GEOMETRY_PRISM_DENSE) : int(GEOMETRY_PRISM_COARSE);
		}
		return dense ? int(GEOMETRY_CONTENTS_DENSE) : int(GEOMETRY_CONTENTS_COARSE);
	});
}

// The oracles of the two models (see EvaluationVariant): the live map with the truth put in where
// the oracle's model would have shown it. p_prism: prism_directions at the scored size.
void compose_oracles(const Cubemap &p_live, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism, Cubemap *r_coarse_oracle,
		Cubemap *r_dense_oracle) {
	*r_coarse_oracle = clone_cubemap(p_live);
	*r_dense_oracle = clone_cubemap(p_live);
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < p_truth.size; y++) {
			const uint8_t *prism = p_prism[size_t(f)].ptr<uint8_t>(y);
			const uint8_t *dense = p_dense[size_t(f)].ptr<uint8_t>(y);
			const cv::Vec3f *truth = p_truth.faces[f].ptr<cv::Vec3f>(y);
			cv::Vec3f *coarse_oracle = r_coarse_oracle->faces[f].ptr<cv::Vec3f>(y);
			cv::Vec3f *dense_oracle = r_dense_oracle->faces[f].ptr<cv::Vec3f>(y);
			for (int x = 0; x < p_truth.size; x++) {
				if (prism[x] && !dense[x]) {
					coarse_oracle[x] = truth[x];
				}
				if (!prism[x]) {
					dense_oracle[x] = truth[x];
				}
			}
		}
	}
}

// EvaluationResult::mirrors at one cubemap: mirror spheres of MIRROR_RADII_M at the probe, read
// from the true map (p_truth with the scene's own distances) and from p_live; a radius that would
// reach into the scene is left out.
void measure_mirrors(const synth::SynthRenderer &p_scene, const Cubemap &p_truth, const Cubemap &p_live, const glm::dvec3 &p_probe, double p_time_s,
		EvaluationResult *r_result) {
	Cubemap true_map = p_truth;
	true_map.distance_m = true_distances(p_scene, p_probe, p_truth.size);
	r_result->mirrors.clear();
	r_result->mirror_clearance_m = std::numeric_limits<double>::infinity();
	for (const cv::Mat &face : true_map.distance_m) {
		double lowest = std::numeric_limits<double>::infinity();
		cv::minMaxLoc(face, &lowest, nullptr, nullptr, nullptr, face > 0.0f); // rays that hit nothing do not count
		r_result->mirror_clearance_m = std::min(r_result->mirror_clearance_m, lowest);
	}
	for (const double radius : MIRROR_RADII_M) {
		if (radius > 0.95 * r_result->mirror_clearance_m) {
			continue; // the sphere would reach into the scene
		}
		for (const bool true_one : { true, false }) {
			r_result->mirrors.push_back({ radius, true_one, mirror_sphere_error(p_scene, true_one ? true_map : p_live, p_probe, radius, p_time_s) });
		}
	}
}

// The stems of the maps written into EvaluationOptions::out, in EvaluationVariant order.
const char *const MAP_FILES[VARIANT_COUNT] = { "baseline", "coarse", "coarse_inpaint", "coarse_light_additive", "coarse_light_gain", "dense_true_poses",
	"dense_slam", "oracle_coarse_texture", "oracle_dense" };
constexpr const char *TRUTH_FILE = "ground_truth";

} // namespace

std::vector<std::string> evaluation_output_files() {
	std::vector<std::string> names;
	for (const char *stem : MAP_FILES) {
		names.push_back(std::string(stem) + ".exr");
		names.push_back(std::string(stem) + ".png");
	}
	names.push_back(std::string(TRUTH_FILE) + ".exr");
	names.push_back(std::string(TRUTH_FILE) + ".png");
	return names;
}

// Why a recording lacks what its writer writes on closing, when it was never closed (issue #38: a
// synth killed midway), as a clause to end an error with; "" otherwise. Said in the error itself:
// --quiet shows no recording issues.
std::string unfinished_note(const RecordingReader &p_reader) {
	for (const RecordingIssue &issue : p_reader.get_issues()) {
		if (std::filesystem::path(issue.file).filename() == recording_io::WRITING_MARKER) {
			return ": " + issue.message;
		}
	}
	return "";
}

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

EvaluationResult evaluate_recording(const EvaluationOptions &p_options) {
	EvaluationResult result;
	auto say = [&](const std::string &p_line) {
		if (p_options.progress) {
			p_options.progress(p_line);
		}
	};
	RecordingReader reader;
	const RecordingStatus status = reader.open(p_options.recording);
	if (!status.ok) {
		result.error = status.error;
		return result;
	}
	// Every problem the reader met, each once (issue #38: they were counted, not listed).
	for (const std::string &line : issue_lines(reader.get_issues())) {
		say("recording issue: " + line);
	}
	if (!reader.has_room()) {
		result.error = p_options.recording + ": no room.yaml (the coarse model needs the floorplan)";
		return result;
	}
	if (!reader.has_ground_truth_trajectory(RecordingStream::Rgbd)) {
		result.error = p_options.recording + ": no ground-truth RGB-D trajectory (PoseSource::GroundTruth needs it)" + unfinished_note(reader);
		return result;
	}
	if (reader.ground_truth_cubemap_count() == 0) {
		result.error = p_options.recording + ": no ground-truth cubemaps";
		return result;
	}
	// Nothing to score from nothing: every variant but the dense ones needs fisheye frames.
	if (reader.fisheye_count() == 0) {
		result.error = p_options.recording + ": no fisheye frames (fisheye.txt lists none)";
		return result;
	}
	if (p_options.dense && reader.rgbd_count() == 0) {
		result.error = p_options.recording + ": no RGB-D frames (rgb.txt and depth.txt list none; --no-dense scores the coarse model alone)";
		return result;
	}
	const Rig &rig = reader.get_rig();
	const RoomInfo &room = reader.get_room();
	const Trajectory &trajectory = reader.ground_truth_trajectory(RecordingStream::Rgbd);

	// synth.yaml: the light switch, and the rig's photometry (a perfect photometric calibration).
	const std::filesystem::path synth_yaml = std::filesystem::path(p_options.recording) / "synth.yaml";
	if (std::filesystem::exists(synth_yaml)) {
		cv::FileStorage info;
		const std::string problem = open_yaml_file(synth_yaml.string(), &info);
		if (!problem.empty()) {
			result.error = problem;
			return result;
		}
		if (!info["light_switch_s"].empty()) {
			result.light_switch_s = double(info["light_switch_s"]);
		}
	}
	RigPhotometry photometry;
	if (p_options.linearise) {
		std::string error;
		if (!read_recording_photometry(p_options.recording, rig.photometry, &photometry, &error)) {
			result.error = error;
			return result;
		}
	}
	result.linearised = photometry.known;
	// The baseline sees the frames as the engines do.
	FisheyeLinearizer linearizer;
	linearizer.configure(photometry, rig.fisheye);

	// The variants, each one LiveRoom in step mode, as the nodes and the benchmark run it: (b, c)
	// share one engine (raw and completed texture), (e, f) another (without and with its dense
	// model fused at the true poses), and (g) is the live system on tracked poses.
	LiveRoomConfig base;
	base.rig = rig;
	base.photometry = photometry;
	base.has_room = true;
	base.floorplan = room.floorplan;
	base.initial_rgb_pose = room.initial_rgb_pose;
	if (!p_options.room_file.empty()) {
		const RoomLoadResult given = load_room_file(p_options.room_file);
		if (!given.ok) {
			result.error = given.error;
			return result;
		}
		base.floorplan = given.room.floorplan;
		base.world_from_room = compose(room.initial_rgb_pose, inverse(given.room.initial_rgb_pose));
		say("the coarse model's room: " + p_options.room_file + " (" + std::to_string(given.room.floorplan.points.size()) + " corners, ceiling " +
				std::to_string(given.room.floorplan.ceiling_height_m) + " m), placed by its initial_rgb_pose");
	}
	base.keep_points = room.probes;
	base.ground_truth = trajectory;
	base.coarse_poses = PoseSource::GroundTruth;
	base.dense_poses = PoseSource::GroundTruth;
	base.dense = false;
	base.coarse.texel_size_m = p_options.texel_size_m;
	base.coarse.inpaint = true;
	base.coarse.inpaint_async = false; // the completed texture belongs to the latest frame
	base.coarse.rgb_texture = p_options.rgb_texture;
	if (p_options.dense_range_m > 0.0) {
		base.slam.tsdf.max_depth_m = float(p_options.dense_range_m);
		base.dense_render_far_m = float(p_options.dense_range_m);
	}
	LiveRoomConfig no_light = base, additive = base, gain = base, tracked = base;
	no_light.coarse.lighting = false;
	additive.coarse.lighting = true;
	additive.coarse.lighting_model = LightingModel::ADDITIVE_PAPER;
	gain.coarse.lighting = true;
	gain.coarse.lighting_model = LightingModel::GAIN_ROBUST;
	gain.dense = p_options.dense;
	tracked = gain;
	tracked.coarse_poses = PoseSource::Tracked;
	tracked.dense_poses = PoseSource::Tracked;
	LiveRoom engine_plain, engine_additive, engine_gain, engine_tracked;
	std::vector<std::pair<LiveRoom *, const LiveRoomConfig *>> engines = { { &engine_plain, &no_light }, { &engine_additive, &additive },
		{ &engine_gain, &gain } };
	if (p_options.dense) {
		engines.emplace_back(&engine_tracked, &tracked);
	}
	for (const auto &[engine, config] : engines) {
		const std::string error = engine->configure(*config);
		if (!error.empty()) {
			result.error = p_options.recording + ": " + error;
			return result;
		}
	}
	const bool dense = p_options.dense;
	// The oracles need the true scene (and the dense variants they start from).
	std::unique_ptr<synth::SynthRenderer> truth_scene;
	if (dense && p_options.oracles) {
		TruthSceneResult loaded = load_truth_scene(p_options.recording);
		if (loaded.ok) {
			truth_scene = std::move(loaded.renderer);
		} else {
			result.no_oracles = loaded.error;
			say("no oracle variants: " + loaded.error);
		}
	} else {
		result.no_oracles = dense ? "not asked for" : "they need the dense variants";
	}
	const int variant_count = dense ? (truth_scene ? VARIANT_COUNT : VARIANT_ORACLE_COARSE_TEXTURE) : VARIANT_DENSE_TRUE_POSES;
	FaceMasks prism_mask; // prism_directions at the scored size, for prism_mask_at
	glm::dvec3 prism_mask_at(std::numeric_limits<double>::quiet_NaN());
	SlamFigures slam_figures;
	double render_ms[3] = { 0.0, 0.0, 0.0 }; // coarse renders of (c), (d), (e), summed

	const GroundTruthCubemapResult first = reader.ground_truth_cubemap(0);
	if (!first.ok) {
		result.error = first.error;
		return result;
	}
	const int size = p_options.cubemap_size > 0 ? p_options.cubemap_size : first.cubemap.faces[0].cols;
	result.cubemap_size = size;
	const int render_size = size * std::max(1, p_options.render_scale); // the maps, area-averaged down to size to be scored
	BaselineEnvmap baseline(size);

	const char *names[VARIANT_COUNT] = { "baseline (5.3)", "coarse", "coarse+inpaint", "+light (additive)", "+light (gain)", "+dense (true poses)",
		"+dense (SLAM)", "oracle: true coarse texture", "oracle: true dense model" };
	result.variants.resize(size_t(variant_count));
	for (int v = 0; v < variant_count; v++) {
		result.variants[v].name = names[v];
	}

	std::unique_ptr<CoarseCubemapRenderer> direction_renderer; // the direction split's, built at the first cubemap
	const std::vector<PlaybackEvent> &events = reader.get_events();
	result.start_s = events.empty() ? 0.0 : events.front().time_s;
	size_t next_event = 0;
	double baseline_total_ms = 0.0, metrics_total_ms = 0.0;
	size_t rgbd_frames_used = 0;
	SkippedFrames fisheye_skipped, rgbd_skipped, cubemaps_skipped; // why, for an error that says so by itself
	size_t comparisons = 0;
	size_t count = reader.ground_truth_cubemap_count();
	if (p_options.max_cubemaps > 0 && p_options.max_cubemaps < count) {
		count = p_options.max_cubemaps;
	}
	for (size_t c = 0; c < count; c++) {
		const CubemapRef &ref = reader.get_ground_truth_cubemap_ref(c);
		// Feed every frame up to this instant, in time order.
		while (next_event < events.size() && events[next_event].time_s <= ref.timestamp_s + 1e-6) {
			const PlaybackEvent &event = events[next_event++];
			if (event.stream == RecordingStream::Rgbd) {
				if (dense) {
					RgbdFrameResult rgbd = reader.read_rgbd(event.index);
					if (rgbd.ok) {
						rgbd_frames_used++;
						engine_gain.push_rgbd(rgbd.frame);
						engine_tracked.push_rgbd(std::move(rgbd.frame));
						slam_figures.add(*engine_tracked.tracked_frame(), trajectory, &result.slam);
					} else {
						say("skipping RGB-D frame: " + rgbd.error);
						rgbd_skipped.add(rgbd.error);
					}
				}
				continue;
			}
			const FrameRef &fref = reader.get_fisheye_ref(event.index);
			Pose pose;
			std::string pose_error;
			if (!fisheye_pose_at(trajectory, rig, fref.timestamp_s, &pose, &pose_error)) {
				say("skipping fisheye frame " + std::to_string(event.index) + ": " + pose_error);
				fisheye_skipped.add("fisheye frame " + std::to_string(event.index) + ": " + pose_error);
				continue;
			}
			FisheyeFrameResult frame = reader.read_fisheye(event.index);
			if (!frame.ok) {
				say("skipping fisheye frame: " + frame.error);
				fisheye_skipped.add(frame.error);
				continue;
			}
			const Clock::time_point start = Clock::now();
			baseline.add_frame(
					linearizer.linearise(frame.frame.image, exposure_ratio(photometry.fisheye, frame.frame.capture.exposure_us, frame.frame.capture.gain)).radiance,
					rig.fisheye, pose);
			baseline_total_ms += ms_since(start);
			for (const auto &[engine, config] : engines) {
				engine->push_fisheye(frame.frame);
			}
			result.fisheye_frames_used++;
		}
		const GroundTruthCubemapResult truth = c == 0 ? first : reader.ground_truth_cubemap(c);
		if (!truth.ok) {
			say("skipping ground-truth cubemap: " + truth.error);
			cubemaps_skipped.add(truth.error);
			continue;
		}
		const Cubemap gt = to_cubemap(truth.cubemap.faces, size);
		const glm::dvec3 probe = truth.cubemap.position;
		Cubemap estimates[VARIANT_COUNT];
		estimates[VARIANT_BASELINE] = baseline.cubemap();
		// The coarse render's time, per engine (the render column of the timings table).
		auto timed = [&](LiveRoom &p_engine, bool p_completed, double *io_ms) {
			const Clock::time_point start = Clock::now();
			Cubemap map = to_cubemap(p_engine.render_at(probe, render_size, p_completed, false).faces, size);
			*io_ms += ms_since(start);
			return map;
		};
		double unused_ms = 0.0;
		estimates[VARIANT_COARSE] = timed(engine_plain, false, &unused_ms);
		estimates[VARIANT_INPAINT] = timed(engine_plain, true, &render_ms[0]);
		estimates[VARIANT_LIGHT_ADDITIVE] = timed(engine_additive, true, &render_ms[1]);
		estimates[VARIANT_LIGHT_GAIN] = timed(engine_gain, true, &render_ms[2]);
		if (dense) {
			estimates[VARIANT_DENSE_TRUE_POSES] = to_cubemap(engine_gain.render_at(probe, render_size, true, true).faces, size);
			DenseRenderStats stats;
			estimates[VARIANT_DENSE_SLAM] = to_cubemap(engine_tracked.render_at(probe, render_size, true, true, &stats), size);
			slam_figures.add_render(stats.milliseconds);
			// Which directions the dense model covers: where the live map differs from its render
			// without the dense pass.
			FaceMasks dense_covers;
			auto covers = [&]() -> const FaceMasks & {
				if (dense_covers[0].empty()) {
					dense_covers = dense_coverage(estimates[VARIANT_DENSE_SLAM], to_cubemap(engine_tracked.render_at(probe, render_size, true, false).faces, size));
				}
				return dense_covers;
			};
			if (truth_scene) {
				if (!(probe == prism_mask_at)) {
					prism_mask = prism_directions(*truth_scene, room.floorplan, probe, size);
					prism_mask_at = probe;
				}
				compose_oracles(estimates[VARIANT_DENSE_SLAM], covers(), gt, prism_mask, &estimates[VARIANT_ORACLE_COARSE_TEXTURE], &estimates[VARIANT_ORACLE_DENSE]);
			}
			// Only at the cubemap the split is reported for: the last at or before 10 s into the sweep
			// (the first, when none is; the last of a shorter recording).
			const double moment_s = result.start_s + SWEEP_MOMENTS_S[2] + 1e-6;
			const bool last_before = c + 1 == count || reader.get_ground_truth_cubemap_ref(c + 1).timestamp_s > moment_s;
			if ((result.directions_at_s < 0.0 || ref.timestamp_s <= moment_s) && last_before) {
				if (!direction_renderer && engine_tracked.room_mesh()) {
					direction_renderer = std::make_unique<CoarseCubemapRenderer>(*engine_tracked.room_mesh());
				}
				if (direction_renderer) {
					split_by_direction(engine_tracked, *direction_renderer, estimates[VARIANT_DENSE_SLAM], covers(), gt, probe, render_size, result.directions);
					if (truth_scene) {
						split_by_geometry(estimates[VARIANT_DENSE_SLAM], covers(), gt, prism_mask, result.geometry);
						measure_mirrors(*truth_scene, gt, estimates[VARIANT_DENSE_SLAM], probe, ref.timestamp_s, &result);
					}
					result.directions_at_s = ref.timestamp_s;
				}
			}
		}
		for (int v = 0; v < variant_count; v++) {
			const Clock::time_point start = Clock::now();
			FrameScore score;
			score.timestamp_s = ref.timestamp_s;
			score.metrics = compare_cubemaps(estimates[v], gt);
			metrics_total_ms += ms_since(start);
			comparisons++;
			result.variants[v].frames.push_back(score);
			result.variants[v].last = estimates[v];
		}
		result.cubemaps++;
		if (c % 10 == 0) {
			char line[160];
			std::snprintf(line, sizeof(line), "cubemap %zu/%zu t=%.3f s: baseline %.2f dB, full %.2f dB", c + 1, count, ref.timestamp_s,
					result.variants[VARIANT_BASELINE].frames.back().metrics.psnr_db, result.variants[VARIANT_LIGHT_GAIN].frames.back().metrics.psnr_db);
			say(line);
		}
		if (c + 1 == count && !p_options.out.empty()) {
			// Every failure is kept, not only said: the caller reports it whether or not it shows
			// the progress lines.
			std::vector<std::string> failed;
			std::error_code ec;
			std::filesystem::create_directories(p_options.out, ec);
			if (ec) {
				failed.push_back(p_options.out + ": cannot create the folder (" + ec.message() + ")");
			}
			auto write = [&](const char *p_stem, const Cubemap &p_map) {
				const std::string stem = (std::filesystem::path(p_options.out) / p_stem).string();
				for (const std::string &error : { write_cubemap_exr(stem + ".exr", p_map), write_cubemap_png_net(stem + ".png", p_map) }) {
					if (!error.empty()) {
						say(error);
						failed.push_back(error);
					}
				}
			};
			for (int v = 0; !ec && v < variant_count; v++) {
				write(MAP_FILES[v], estimates[v]);
			}
			if (!ec) {
				write(TRUTH_FILE, gt);
			}
			if (!failed.empty()) {
				result.out_error = failed.front() +
						(failed.size() > 1 ? " (and " + std::to_string(failed.size() - 1) + " more of the maps could not be written)" : std::string());
			}
		}
	}
	if (result.cubemaps == 0) {
		result.error = p_options.recording + ": no ground-truth cubemap could be evaluated: " + std::to_string(cubemaps_skipped.count) + " skipped; the first: " +
				cubemaps_skipped.first;
		return result;
	}
	// The reason is in the message itself: "see the messages above" pointed at progress lines that
	// --quiet and the nodes never show (issue #38).
	const double last_cubemap_s = reader.get_ground_truth_cubemap_ref(count - 1).timestamp_s;
	if (result.fisheye_frames_used == 0) {
		result.error = p_options.recording + ": none of its " + std::to_string(reader.fisheye_count()) + " fisheye frames could be used: " +
				fisheye_skipped.describe(last_cubemap_s);
		return result;
	}
	if (dense && rgbd_frames_used == 0) {
		result.error = p_options.recording + ": none of its " + std::to_string(reader.rgbd_count()) + " RGB-D frames could be read: " +
				rgbd_skipped.describe(last_cubemap_s);
		return result;
	}
	for (VariantScores &v : result.variants) {
		double after_psnr = 0.0, after_ssim = 0.0, after_linear = 0.0, after_irradiance = 0.0;
		for (const FrameScore &f : v.frames) {
			v.mean_psnr_db += f.metrics.psnr_db;
			v.mean_ssim += f.metrics.ssim;
			v.mean_psnr_linear_db += f.metrics.psnr_linear_db;
			v.mean_ssim_linear += f.metrics.ssim_linear;
			v.mean_irradiance_error += f.metrics.irradiance_error;
			v.mean_psnr_mu_db += f.metrics.psnr_mu_db;
			v.mean_psnr_worst5_db += f.metrics.psnr_worst5_db;
			for (int m = 0; m < 3; m++) {
				if (f.timestamp_s <= result.start_s + SWEEP_MOMENTS_S[m] + 1e-6) {
					v.at_moment[m] = int(&f - v.frames.data());
				}
			}
			if (result.light_switch_s >= 0.0 && f.timestamp_s > result.light_switch_s) {
				v.after_switch_frames++;
				after_psnr += f.metrics.psnr_db;
				after_ssim += f.metrics.ssim;
				after_linear += f.metrics.psnr_linear_db;
				after_irradiance += f.metrics.irradiance_error;
			}
		}
		const double n = double(v.frames.size());
		v.mean_psnr_db /= n;
		v.mean_ssim /= n;
		v.mean_psnr_linear_db /= n;
		v.mean_ssim_linear /= n;
		v.mean_irradiance_error /= n;
		v.mean_psnr_mu_db /= n;
		v.mean_psnr_worst5_db /= n;
		// A moment past the recording's end has no frame.
		const double end_s = v.frames.empty() ? 0.0 : v.frames.back().timestamp_s;
		for (int m = 0; m < 3; m++) {
			if (result.start_s + SWEEP_MOMENTS_S[m] > end_s + 0.5) {
				v.at_moment[m] = -1;
			}
		}
		if (v.after_switch_frames > 0) {
			const double after = double(v.after_switch_frames);
			v.after_switch_psnr_db = after_psnr / after;
			v.after_switch_ssim = after_ssim / after;
			v.after_switch_psnr_linear_db = after_linear / after;
			v.after_switch_irradiance_error = after_irradiance / after;
		}
	}
	const double per_frame = result.fisheye_frames_used > 0 ? 1.0 / double(result.fisheye_frames_used) : 0.0;
	add_timings(&result.timings_inpaint, engine_plain.coarse_model()->total_timings(), per_frame);
	add_timings(&result.timings_additive, engine_additive.coarse_model()->total_timings(), per_frame);
	add_timings(&result.timings_gain, engine_gain.coarse_model()->total_timings(), per_frame);
	const double per_cubemap = 1.0 / double(result.cubemaps);
	result.timings_inpaint.render_ms = render_ms[0] * per_cubemap;
	result.timings_additive.render_ms = render_ms[1] * per_cubemap;
	result.timings_gain.render_ms = render_ms[2] * per_cubemap;
	result.baseline_ms = baseline_total_ms * per_frame;
	result.metrics_ms = comparisons > 0 ? metrics_total_ms / double(comparisons) : 0.0;
	if (dense) {
		slam_figures.finish(&result.slam);
	}
	result.ok = true;
	return result;
}

// The live system's map split by DirectionClass, as lines (nothing when it was not measured).
std::string format_directions(const EvaluationResult &p_result) {
	if (p_result.directions_at_s < 0.0) {
		return "";
	}
	std::ostringstream out;
	char line[200];
	std::snprintf(line, sizeof(line), "+dense (SLAM) by direction at t = %.2f s (%.1f s into the sweep): share of the map, tone-mapped PSNR\n",
			p_result.directions_at_s, p_result.directions_at_s - p_result.start_s);
	out << line;
	const char *classes[DIRECTION_CLASS_COUNT] = { "seen by the fisheye", "saturated in the fisheye", "seen only by the RGB-D camera", "never seen (inpainted)" };
	for (int c = 0; c < DIRECTION_CLASS_COUNT; c++) {
		std::snprintf(line, sizeof(line), "  %-32s %6.1f %%  %6.2f dB\n", classes[c], 100.0 * p_result.directions[c].share, p_result.directions[c].psnr_db);
		out << line;
	}
	if (p_result.no_oracles.empty() && p_result.mirrors.size() < 2 * std::size(MIRROR_RADII_M)) {
		std::snprintf(line, sizeof(line), "mirror spheres wider than %.3f m left out: the scene is that near the probe\n", 0.95 * p_result.mirror_clearance_m);
		out << line;
	}
	if (p_result.no_oracles.empty()) {
		out << "the same map by what the direction truly sees, and what shows it:\n";
		const char *geometry[GEOMETRY_CLASS_COUNT] = { "the room's prism, coarse model", "the room's prism, dense model", "what stands in it, dense model",
			"what stands in it, coarse model" };
		for (int c = 0; c < GEOMETRY_CLASS_COUNT; c++) {
			std::snprintf(line, sizeof(line), "  %-32s %6.1f %%  %6.2f dB\n", geometry[c], 100.0 * p_result.geometry[c].share, p_result.geometry[c].psnr_db);
			out << line;
		}
	}
	for (const EvaluationResult::MirrorRow &row : p_result.mirrors) {
		std::snprintf(line, sizeof(line), "mirror sphere r = %.2f m, %s map (%d views, %zu px): %6.2f dB read along the reflection, %6.2f dB distance-aware\n",
				row.radius_m, row.true_map ? "true" : "live", row.scores.views, row.scores.pixels, row.scores.psnr_plain_db, row.scores.psnr_parallax_db);
		out << line;
	}
	return out.str();
}

BudgetResult error_budget(const EvaluationOptions &p_options) {
	BudgetResult budget;
	struct Run {
		const char *label;
		std::function<void(EvaluationOptions *)> change;
		std::vector<std::pair<EvaluationVariant, const char *>> rows;
	};
	const Run runs[] = {
		{ "as shipped", [](EvaluationOptions *) {},
				{ { VARIANT_DENSE_SLAM, "the live system: SLAM poses, dense over the coarse model, inpainting, gain lighting" },
						{ VARIANT_DENSE_TRUE_POSES, "oracle: true poses" }, { VARIANT_LIGHT_GAIN, "without the dense model (true poses)" },
						{ VARIANT_COARSE, "without inpainting, lighting or dense (true poses)" },
						{ VARIANT_ORACLE_COARSE_TEXTURE, "oracle: true coarse texture where the prism is the true geometry (SLAM poses)" },
						{ VARIANT_ORACLE_DENSE, "oracle: true dense geometry and colours (SLAM poses)" } } },
		{ "2x resolution",
				[](EvaluationOptions *o) {
					o->texel_size_m /= 2.0;
					o->render_scale = 2;
					o->oracles = false;
				},
				{ { VARIANT_DENSE_SLAM, "oracle: texels and maps at twice the resolution (SLAM poses)" },
						{ VARIANT_DENSE_TRUE_POSES, "oracle: twice the resolution and true poses" } } },
		{ "no photometry",
				[](EvaluationOptions *o) {
					o->linearise = false;
					o->oracles = false;
				},
				{ { VARIANT_DENSE_SLAM, "without photometric calibration (frames as recorded, SLAM poses)" } } },
		{ "RGB texturing",
				[](EvaluationOptions *o) {
					o->rgb_texture = true;
					o->oracles = false;
				},
				{ { VARIANT_DENSE_SLAM, "with the RGB camera's texturing of the coarse model (SLAM poses)" },
						{ VARIANT_LIGHT_GAIN, "with RGB texturing, without the dense model (true poses)" } } },
	};
	for (const Run &run : runs) {
		EvaluationOptions options = p_options;
		options.dense = true;
		options.out.clear();
		run.change(&options);
		if (p_options.progress) {
			p_options.progress(std::string("budget: evaluating ") + run.label);
		}
		const EvaluationResult result = evaluate_recording(options);
		if (!result.ok) {
			budget.error = result.error;
			return budget;
		}
		budget.start_s = result.start_s;
		budget.cubemap_size = result.cubemap_size;
		if (budget.rows.empty()) {
			budget.shipped = result;
			budget.shipped.variants.clear(); // the rows keep what the table needs
		}
		for (const auto &[variant, what] : run.rows) {
			if (size_t(variant) >= result.variants.size()) {
				budget.missing.push_back(std::string(what) + ": " + result.no_oracles);
				continue;
			}
			BudgetRow row;
			row.what = what;
			row.scores = result.variants[size_t(variant)];
			budget.rows.push_back(row);
		}
	}
	budget.ok = true;
	return budget;
}

std::string format_budget(const BudgetResult &p_budget) {
	if (!p_budget.ok) {
		return "budget failed: " + p_budget.error + "\n";
	}
	std::ostringstream out;
	char line[320];
	std::snprintf(line, sizeof(line), "error budget (%d px faces): each row replaces one stage of the live system by its oracle, or leaves one out\n",
			p_budget.cubemap_size);
	out << line;
	std::snprintf(line, sizeof(line), "%-86s %9s %9s %9s %9s %9s\n", "", "PSNR", "PSNR", "PSNRmu", "worst 5%", "Eirr");
	out << line;
	std::snprintf(line, sizeof(line), "%-86s %9s %9s %9s %9s %9s\n", "row", "mean[dB]", "10 s[dB]", "10 s[dB]", "10 s[dB]", "10 s[%]");
	out << line;
	for (const BudgetRow &row : p_budget.rows) {
		const VariantScores &v = row.scores;
		const int at = v.at_moment[2] >= 0 ? v.at_moment[2] : (v.frames.empty() ? -1 : int(v.frames.size()) - 1);
		const CubemapMetrics m = at >= 0 ? v.frames[size_t(at)].metrics : CubemapMetrics();
		std::snprintf(line, sizeof(line), "%-86s %9.2f %9.2f %9.2f %9.2f %9.2f\n", row.what.c_str(), v.mean_psnr_db, m.psnr_db, m.psnr_mu_db, m.psnr_worst5_db,
				100.0 * m.irradiance_error);
		out << line;
	}
	for (const std::string &missing : p_budget.missing) {
		out << "not measured: " << missing << "\n";
	}
	out << format_directions(p_budget.shipped);
	const bool short_recording = !p_budget.rows.empty() && p_budget.rows[0].scores.at_moment[2] < 0;
	if (short_recording) {
		out << "(the recording is shorter than 10 s: the '10 s' columns are its last cubemap)\n";
	}
	return out.str();
}

std::string format_evaluation(const EvaluationResult &p_result, bool p_per_frame) {
	std::ostringstream out;
	char line[256];
	if (!p_result.ok) {
		return "evaluation failed: " + p_result.error + "\n";
	}
	if (p_per_frame) {
		out << "per frame: t [s], then PSNR [dB] / SSIM / irradiance error [%] of each variant\n";
		const size_t n = p_result.variants[0].frames.size();
		for (size_t i = 0; i < n; i++) {
			std::snprintf(line, sizeof(line), "%8.3f", p_result.variants[0].frames[i].timestamp_s);
			out << line;
			for (const VariantScores &v : p_result.variants) {
				std::snprintf(line, sizeof(line), "  %6.2f/%.4f/%.1f", v.frames[i].metrics.psnr_db, v.frames[i].metrics.ssim, 100.0 * v.frames[i].metrics.irradiance_error);
				out << line;
			}
			out << "\n";
		}
	}
	std::snprintf(line, sizeof(line), "%zu cubemaps (%d px faces), %zu fisheye frames, poses: ground truth, frames %s\n", p_result.cubemaps,
			p_result.cubemap_size, p_result.fisheye_frames_used, p_result.linearised ? "linearised" : "as recorded");
	out << line;
	std::snprintf(line, sizeof(line), "%-27s %10s %8s %12s %10s %9s %10s %10s\n", "variant", "PSNR[dB]", "SSIM", "PSNRlin[dB]", "SSIMlin", "Eirr[%]",
			"PSNRmu[dB]", "worst5[dB]");
	out << line;
	for (const VariantScores &v : p_result.variants) {
		std::snprintf(line, sizeof(line), "%-27s %10.2f %8.4f %12.2f %10.4f %9.2f %10.2f %10.2f\n", v.name.c_str(), v.mean_psnr_db, v.mean_ssim,
				v.mean_psnr_linear_db, v.mean_ssim_linear, 100.0 * v.mean_irradiance_error, v.mean_psnr_mu_db, v.mean_psnr_worst5_db);
		out << line;
	}
	out << "into the sweep (the last cubemap at or before each moment): PSNR / PSNRmu / worst 5 % [dB], Eirr [%]\n";
	std::snprintf(line, sizeof(line), "%-27s", "variant");
	out << line;
	for (double moment : SWEEP_MOMENTS_S) {
		std::snprintf(line, sizeof(line), " %27s", ("at " + std::to_string(int(moment)) + " s").c_str());
		out << line;
	}
	out << "\n";
	for (const VariantScores &v : p_result.variants) {
		std::snprintf(line, sizeof(line), "%-27s", v.name.c_str());
		out << line;
		for (int m = 0; m < 3; m++) {
			if (v.at_moment[m] < 0) {
				std::snprintf(line, sizeof(line), " %27s", "(recording too short)");
			} else {
				const CubemapMetrics &f = v.frames[size_t(v.at_moment[m])].metrics;
				std::snprintf(line, sizeof(line), " %5.2f/%5.2f/%5.2f, %6.2f%%", f.psnr_db, f.psnr_mu_db, f.psnr_worst5_db, 100.0 * f.irradiance_error);
			}
			out << line;
		}
		out << "\n";
	}
	if (p_result.light_switch_s >= 0.0) {
		std::snprintf(line, sizeof(line), "after the light switch (t > %.3f s, cubemap metrics, %zu frames):\n", p_result.light_switch_s,
				p_result.variants[0].after_switch_frames);
		out << line;
		for (const VariantScores &v : p_result.variants) {
			std::snprintf(line, sizeof(line), "%-27s %10.2f %8.4f %12.2f %10s %9.2f\n", v.name.c_str(), v.after_switch_psnr_db, v.after_switch_ssim,
					v.after_switch_psnr_linear_db, "", 100.0 * v.after_switch_irradiance_error);
			out << line;
		}
	}
	out << "per-stage timings, ms per fisheye frame (render: per cubemap):\n";
	std::snprintf(line, sizeof(line), "%-27s %9s %9s %9s %9s %9s %9s\n", "pipeline", "occlusion", "lighting", "update", "inpaint", "frame", "render");
	out << line;
	const std::pair<const char *, const CoarsePipelineTimings *> rows[] = { { "inpaint, no light", &p_result.timings_inpaint },
		{ "light (additive)", &p_result.timings_additive }, { "light (gain)", &p_result.timings_gain } };
	for (const auto &[name, t] : rows) {
		std::snprintf(line, sizeof(line), "%-27s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f\n", name, t->occlusion_ms, t->lighting_ms, t->update_ms,
				t->inpaint_ms, t->frame_ms, t->render_ms);
		out << line;
	}
	std::snprintf(line, sizeof(line), "baseline add_frame %.2f ms per frame; metrics %.2f ms per comparison\n", p_result.baseline_ms, p_result.metrics_ms);
	out << line;
	out << format_directions(p_result);
	const SlamScores &slam = p_result.slam;
	if (slam.frames > 0) {
		std::snprintf(line, sizeof(line),
				"SLAM (+dense (SLAM)): %zu RGB-D frames, %zu good, %zu poor, %zu lost; ATE RMSE %.2f mm, max %.2f mm (against the ground truth, no alignment)\n",
				slam.frames, slam.good, slam.poor, slam.lost, slam.ate_rmse_m * 1000.0, slam.ate_max_m * 1000.0);
		out << line;
		std::snprintf(line, sizeof(line), "SLAM ms per RGB-D frame: tracking %.2f, integration %.2f, raycast %.2f; dense cubemap pass %.2f ms\n", slam.track_ms,
				slam.integrate_ms, slam.raycast_ms, slam.dense_render_ms);
		out << line;
	}
	return out.str();
}

} // namespace roomprobe
