// evaluate_recording (evaluate.h): the variants' engines fed a recording's frames in time order
// and scored at each ground-truth cubemap, one step of RecordingEvaluation (evaluate_internal.h)
// after another; and the error budget, four such evaluations. Each cubemap's step is in
// evaluate_cubemap.cpp, the per-class scoring and the oracles in evaluate_classes.cpp, the reports
// in evaluate_report.cpp.

#include "evaluate_internal.h"
#include "truth_scene.h"

#include <io/yaml_fields.h>

#include <engine/engine_config.h>
#include <engine/live_room.h>
#include <envmap/baseline.h>
#include <recording/recording_io.h>
#include <recording/recording_reader.h>
#include <recording/room_file.h>
#include <rig/fisheye_pose.h>
#include <rig/photometry.h>
#include <source/recording_player.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace roomprobe {

namespace {

// p_total, a pipeline's summed timings, scaled to a mean.
void add_timings(CoarsePipelineTimings *r_sum, const CoarsePipelineTimings &p_total, double p_scale) {
	r_sum->occlusion_ms = p_total.occlusion_ms * p_scale;
	r_sum->lighting_ms = p_total.lighting_ms * p_scale;
	r_sum->update_ms = p_total.update_ms * p_scale;
	r_sum->inpaint_ms = p_total.inpaint_ms * p_scale;
	r_sum->render_ms = p_total.render_ms * p_scale;
	r_sum->sh_ms = p_total.sh_ms * p_scale;
	r_sum->frame_ms = p_total.frame_ms * p_scale;
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

// A variant's scores over its frames: the means, the frames at the sweep's moments, and the means
// after the light switch.
void summarise_variant(double p_start_s, double p_light_switch_s, VariantScores *r_scores) {
	VariantScores &v = *r_scores;
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
			if (f.timestamp_s <= p_start_s + SWEEP_MOMENTS_S[m] + 1e-6) {
				v.at_moment[m] = int(&f - v.frames.data());
			}
		}
		if (p_light_switch_s >= 0.0 && f.timestamp_s > p_light_switch_s) {
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
		if (p_start_s + SWEEP_MOMENTS_S[m] > end_s + 0.5) {
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

} // namespace

namespace evaluate_detail {

void RecordingEvaluation::run() {
	if (!open_recording() || !read_light_switch() || !build_base_config() || !configure_engines()) {
		return;
	}
	load_oracles();
	if (!start_scoring()) {
		return;
	}
	for (size_t c = 0; c < count; c++) {
		evaluate_cubemap(c);
	}
	if (finish()) {
		result.ok = true;
	}
}

void RecordingEvaluation::say(const std::string &p_line) const {
	if (options.progress) {
		options.progress(p_line);
	}
}

// Opens the recording and checks it holds what every variant needs.
bool RecordingEvaluation::open_recording() {
	PlayerOptions play;
	play.rgbd = options.dense || options.no_fisheye; // the coarse variants read RGB-D frames only without a fisheye
	const std::string opened = open_player(options.recording, play, &player);
	if (opened.empty() && !play.rgbd && !player.reader().get_rig().has_fisheye()) {
		play.rgbd = true; // a recording of an RGB-D camera alone: its frames are the coarse model's views
		player = RecordingPlayer(player.shared_reader(), play); // the same reader, not read again
	}
	if (!opened.empty()) {
		result.error = opened;
		return false;
	}
	// Every problem the reader met, each once (issue #38: they were counted, not listed).
	for (const std::string &line : issue_lines(reader().get_issues())) {
		say("recording issue: " + line);
	}
	if (!reader().has_room()) {
		result.error = options.recording + ": no room.yaml (the coarse model needs the floorplan)";
		return false;
	}
	if (!reader().has_ground_truth_trajectory(RecordingStream::Rgbd)) {
		result.error = options.recording + ": no ground-truth RGB-D trajectory (PoseSource::GroundTruth needs it)" + unfinished_note(reader());
		return false;
	}
	if (reader().ground_truth_cubemap_count() == 0) {
		result.error = options.recording + ": no ground-truth cubemaps";
		return false;
	}
	// Nothing to score from nothing: every variant but the dense ones needs fisheye frames.
	no_fisheye = options.no_fisheye || !reader().get_rig().has_fisheye();
	if (reader().fisheye_count() == 0 && !no_fisheye) {
		result.error = options.recording + ": no fisheye frames (fisheye.txt lists none)";
		return false;
	}
	if (options.dense && reader().rgbd_count() == 0) {
		result.error = options.recording + ": no RGB-D frames (rgb.txt and depth.txt list none; --no-dense scores the coarse model alone)";
		return false;
	}
	return true;
}

// synth.yaml's light switch (the rig's photometry in it is config_from_recording's).
bool RecordingEvaluation::read_light_switch() {
	const std::filesystem::path synth_yaml = std::filesystem::path(options.recording) / "synth.yaml";
	if (std::filesystem::exists(synth_yaml)) {
		cv::FileStorage info;
		const std::string problem = open_yaml_file(synth_yaml.string(), &info);
		if (!problem.empty()) {
			result.error = problem;
			return false;
		}
		if (!info["light_switch_s"].empty()) {
			result.light_switch_s = double(info["light_switch_s"]);
		}
	}
	return true;
}

// What the variants share: the recording's configuration (its photometry a perfect photometric
// calibration), the room (or options.room_file's), the true poses and options' settings.
bool RecordingEvaluation::build_base_config() {
	if (options.linearise) {
		const std::string config_error = config_from_recording(reader(), true, &base);
		if (!config_error.empty()) {
			result.error = config_error;
			return false;
		}
	} else {
		config_from_recording(reader(), RigPhotometry(), true, &base); // the frames as recorded
	}
	result.linearised = base.photometry.known;
	linearizer.configure(base.photometry, reader().get_rig().fisheye);
	if (!options.room_file.empty()) {
		const RoomLoadResult given = load_room_file(options.room_file);
		if (!given.ok) {
			result.error = given.error;
			return false;
		}
		base.floorplan = given.room.floorplan;
		base.world_from_room = compose(reader().get_room().initial_rgb_pose, inverse(given.room.initial_rgb_pose));
		say("the coarse model's room: " + options.room_file + " (" + std::to_string(given.room.floorplan.points.size()) + " corners, ceiling " +
				std::to_string(given.room.floorplan.ceiling_height_m) + " m), placed by its initial_rgb_pose");
	}
	base.coarse_poses = PoseSource::GroundTruth;
	base.dense_poses = PoseSource::GroundTruth;
	base.dense = false;
	base.compute_backend = options.compute_backend;
	base.coarse.texel_size_m = options.texel_size_m;
	base.coarse.inpaint = true;
	base.coarse.inpaint_async = false; // the completed texture belongs to the latest frame
	base.coarse.rgb_texture = options.rgb_texture;
	if (no_fisheye) {
		base.rig = rgbd_camera_alone(base.rig); // the RGB camera's response stays known (base.photometry)
	}
	if (options.dense_scale > 0) {
		base.dense_render_scale = options.dense_scale;
	}
	if (options.dense_range_m > 0.0) {
		base.slam.tsdf.max_depth_m = float(options.dense_range_m);
		base.dense_render_far_m = float(options.dense_range_m);
	}
	return true;
}

// Each engine's configuration from base, and the engines configured.
bool RecordingEvaluation::configure_engines() {
	no_light = additive = gain = tracked = base;
	no_light.coarse.lighting = false;
	additive.coarse.lighting = true;
	additive.coarse.lighting_model = LightingModel::ADDITIVE_PAPER;
	gain.coarse.lighting = true;
	gain.coarse.lighting_model = LightingModel::GAIN_ROBUST;
	gain.coarse.lighting_options.field_prior_per_m = options.lighting_field_prior_per_m;
	gain.dense = options.dense;
	tracked = gain;
	tracked.coarse_poses = PoseSource::Tracked;
	tracked.dense_poses = PoseSource::Tracked;
	engines = { { &engine_plain, &no_light }, { &engine_additive, &additive }, { &engine_gain, &gain } };
	if (options.dense) {
		engines.emplace_back(&engine_tracked, &tracked);
	}
	for (const auto &[engine, config] : engines) {
		const std::string error = engine->configure(*config);
		if (!error.empty()) {
			result.error = options.recording + ": " + error;
			return false;
		}
	}
	return true;
}

// The true scene for the oracle variants, and so how many variants there are.
void RecordingEvaluation::load_oracles() {
	if (options.dense && options.oracles) {
		TruthSceneResult loaded = load_truth_scene(options.recording);
		if (loaded.ok) {
			truth_scene = std::move(loaded.renderer);
		} else {
			result.no_oracles = loaded.error;
			say("no oracle variants: " + loaded.error);
		}
	} else {
		result.no_oracles = options.dense ? "not asked for" : "they need the dense variants";
	}
	variant_count = options.dense ? (truth_scene ? VARIANT_COUNT : VARIANT_ORACLE_COARSE_TEXTURE) : VARIANT_DENSE_TRUE_POSES;
}

// The first ground-truth cubemap gives the scored size; the variants' rows, the sweep's start and
// the number of cubemaps to score.
bool RecordingEvaluation::start_scoring() {
	first = reader().ground_truth_cubemap(0);
	if (!first.ok) {
		result.error = first.error;
		return false;
	}
	size = options.cubemap_size > 0 ? options.cubemap_size : first.cubemap.faces[0].cols;
	result.cubemap_size = size;
	render_size = size * std::max(1, options.render_scale);
	baseline.emplace(size);
	const char *names[VARIANT_COUNT] = { "baseline (5.3)", "coarse", "coarse+inpaint", "+light (additive)", "+light (gain)", "+dense (true poses)",
		"+dense (SLAM)", "oracle: true coarse texture", "oracle: true dense model" };
	result.variants.resize(size_t(variant_count));
	for (int v = 0; v < variant_count; v++) {
		result.variants[v].name = names[v];
	}
	result.start_s = player.start_s();
	count = reader().ground_truth_cubemap_count();
	if (options.max_cubemaps > 0 && options.max_cubemaps < count) {
		count = options.max_cubemaps;
	}
	return true;
}

// Feeds every frame up to p_time_s, in time order.
void RecordingEvaluation::feed_until(double p_time_s) {
	for (size_t e : player.take_until(p_time_s)) {
		if (player.events()[e].stream != RecordingStream::Rgbd) {
			feed_fisheye(e);
			continue;
		}
		SourceFrame rgbd = player.read(e);
		if (rgbd.ok) {
			rgbd_frames_used++;
			if (no_fisheye) { // the coarse-only engines' views
				engine_plain.push_rgbd(rgbd.rgbd);
				engine_additive.push_rgbd(rgbd.rgbd);
			}
			engine_gain.push_rgbd(rgbd.rgbd);
			if (options.dense) { // the SLAM engine is configured only then
				engine_tracked.push_rgbd(std::move(rgbd.rgbd));
				slam_figures.add(*engine_tracked.tracked_frame(), reader().ground_truth_trajectory(RecordingStream::Rgbd), &result.slam);
			}
		} else {
			say("skipping RGB-D frame: " + rgbd.error);
			rgbd_skipped.add(rgbd.error);
		}
	}
}

// One fisheye frame into the baseline, at its true pose, and into every engine.
void RecordingEvaluation::feed_fisheye(size_t p_event) {
	const PlaybackEvent &event = player.events()[p_event];
	const Rig &rig = reader().get_rig();
	const FrameRef &fref = reader().get_fisheye_ref(event.index);
	Pose pose;
	std::string pose_error;
	if (!fisheye_pose_at(reader().ground_truth_trajectory(RecordingStream::Rgbd), rig, fref.timestamp_s, &pose, &pose_error)) {
		say("skipping fisheye frame " + std::to_string(event.index) + ": " + pose_error);
		fisheye_skipped.add("fisheye frame " + std::to_string(event.index) + ": " + pose_error);
		return;
	}
	SourceFrame frame = player.read(p_event);
	if (!frame.ok) {
		say("skipping fisheye frame: " + frame.error);
		fisheye_skipped.add(frame.error);
		return;
	}
	const RigPhotometry &photometry = base.photometry;
	const Clock::time_point start = Clock::now();
	baseline->add_frame(
			linearizer.linearise(frame.fisheye.image, exposure_ratio(photometry.fisheye, frame.fisheye.capture.exposure_us, frame.fisheye.capture.gain)).radiance,
			rig.fisheye, pose);
	baseline_total_ms += ms_since(start);
	if (!no_fisheye) {
		for (const auto &[engine, config] : engines) {
			engine->push_fisheye(frame.fisheye);
		}
	}
	result.fisheye_frames_used++;
}

// The result's errors when nothing could be scored, its means and its per-frame timings.
bool RecordingEvaluation::finish() {
	if (result.cubemaps == 0) {
		result.error = options.recording + ": no ground-truth cubemap could be evaluated: " + std::to_string(cubemaps_skipped.count) + " skipped; the first: " +
				cubemaps_skipped.first;
		return false;
	}
	// The reason is in the message itself: "see the messages above" pointed at progress lines that
	// --quiet and the nodes never show (issue #38).
	const double last_cubemap_s = reader().get_ground_truth_cubemap_ref(count - 1).timestamp_s;
	if (result.fisheye_frames_used == 0 && reader().fisheye_count() > 0) {
		result.error = options.recording + ": none of its " + std::to_string(reader().fisheye_count()) + " fisheye frames could be used: " +
				fisheye_skipped.describe(last_cubemap_s);
		return false;
	}
	if (options.dense && rgbd_frames_used == 0) {
		result.error = options.recording + ": none of its " + std::to_string(reader().rgbd_count()) + " RGB-D frames could be read: " +
				rgbd_skipped.describe(last_cubemap_s);
		return false;
	}
	for (VariantScores &v : result.variants) {
		summarise_variant(result.start_s, result.light_switch_s, &v);
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
	if (options.dense) {
		slam_figures.finish(&result.slam);
		result.compute = engine_tracked.stats().compute;
	}
	return true;
}

} // namespace evaluate_detail

using namespace evaluate_detail;

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

EvaluationResult evaluate_recording(const EvaluationOptions &p_options) {
	RecordingEvaluation evaluation(p_options);
	evaluation.run();
	return evaluation.take_result();
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

} // namespace roomprobe
