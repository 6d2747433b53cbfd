// evaluate_recording's step at one ground-truth cubemap (RecordingEvaluation, evaluate_internal.h):
// every variant rendered at its probe, the dense variants' oracles and splits, the scores, and the
// last cubemap's maps written.

#include "evaluate_internal.h"
#include "truth_scene.h"

#include <envmap/coarse_render.h>
#include <envmap/export.h>
#include <recording/recording_reader.h>

#include <filesystem>
#include <system_error>

namespace roomprobe::evaluate_detail {

// Cubemap p_index: the frames up to it fed, every variant rendered at its probe and scored, and
// after the last, the maps written.
void RecordingEvaluation::evaluate_cubemap(size_t p_index) {
	const CubemapRef &ref = reader().get_ground_truth_cubemap_ref(p_index);
	feed_until(ref.timestamp_s);
	const GroundTruthCubemapResult truth = p_index == 0 ? first : reader().ground_truth_cubemap(p_index);
	if (!truth.ok) {
		say("skipping ground-truth cubemap: " + truth.error);
		cubemaps_skipped.add(truth.error);
		return;
	}
	const Cubemap gt = to_cubemap(truth.cubemap.faces, size);
	const glm::dvec3 probe = truth.cubemap.position;
	Estimates estimates;
	render_variants(probe, estimates);
	if (options.dense) {
		render_dense(p_index, ref.timestamp_s, gt, probe, estimates);
	}
	score_variants(ref.timestamp_s, gt, estimates);
	result.cubemaps++;
	if (p_index % 10 == 0) {
		char line[160];
		std::snprintf(line, sizeof(line), "cubemap %zu/%zu t=%.3f s: baseline %.2f dB, full %.2f dB", p_index + 1, count, ref.timestamp_s,
				result.variants[VARIANT_BASELINE].frames.back().metrics.psnr_db, result.variants[VARIANT_LIGHT_GAIN].frames.back().metrics.psnr_db);
		say(line);
	}
	if (p_index + 1 == count && !options.out.empty()) {
		write_maps(estimates, gt);
	}
}

// The baseline and the coarse variants at p_probe.
void RecordingEvaluation::render_variants(const glm::dvec3 &p_probe, Estimates &r_estimates) {
	r_estimates[VARIANT_BASELINE] = baseline->cubemap();
	// The coarse render's time, per engine (the render column of the timings table).
	auto timed = [&](LiveRoom &p_engine, bool p_completed, double *io_ms) {
		const Clock::time_point start = Clock::now();
		Cubemap map = to_cubemap(p_engine.render_at(p_probe, render_size, p_completed, false).faces, size);
		*io_ms += ms_since(start);
		return map;
	};
	double unused_ms = 0.0;
	r_estimates[VARIANT_COARSE] = timed(engine_plain, false, &unused_ms);
	r_estimates[VARIANT_INPAINT] = timed(engine_plain, true, &render_ms[0]);
	r_estimates[VARIANT_LIGHT_ADDITIVE] = timed(engine_additive, true, &render_ms[1]);
	r_estimates[VARIANT_LIGHT_GAIN] = timed(engine_gain, true, &render_ms[2]);
}

// The dense variants and the oracles at p_probe; at the cubemap splits_at picks, the live map's
// direction and geometry splits and the mirror spheres.
void RecordingEvaluation::render_dense(size_t p_index, double p_time_s, const Cubemap &p_truth, const glm::dvec3 &p_probe, Estimates &r_estimates) {
	r_estimates[VARIANT_DENSE_TRUE_POSES] = to_cubemap(engine_gain.render_at(p_probe, render_size, true, true).faces, size);
	DenseRenderStats stats;
	r_estimates[VARIANT_DENSE_SLAM] = to_cubemap(engine_tracked.render_at(p_probe, render_size, true, true, &stats), size);
	const Cubemap &live = r_estimates[VARIANT_DENSE_SLAM];
	slam_figures.add_render(stats.milliseconds);
	FaceMasks covers; // dense_covers', rendered when first needed
	if (truth_scene) {
		if (!(p_probe == prism_mask_at)) {
			prism_mask = prism_directions(*truth_scene, reader().get_room().floorplan, p_probe, size);
			prism_mask_at = p_probe;
		}
		compose_oracles(live, dense_covers(live, p_probe, &covers), p_truth, prism_mask, &r_estimates[VARIANT_ORACLE_COARSE_TEXTURE],
				&r_estimates[VARIANT_ORACLE_DENSE]);
	}
	if (!splits_at(p_index, p_time_s)) {
		return;
	}
	// The direction split renders its masks through the engine's own coarse renderer.
	const CoarseCubemapRenderer *direction_renderer = engine_tracked.probe_renderer() ? engine_tracked.probe_renderer()->coarse_renderer() : nullptr;
	if (direction_renderer == nullptr) {
		return;
	}
	split_by_direction(engine_tracked, *direction_renderer, live, dense_covers(live, p_probe, &covers), p_truth, p_probe, render_size, result.directions);
	if (truth_scene) {
		split_by_geometry(live, dense_covers(live, p_probe, &covers), p_truth, prism_mask, result.geometry);
		measure_mirrors(*truth_scene, p_truth, live, p_probe, p_time_s, &result);
	}
	result.directions_at_s = p_time_s;
}

// Which directions the dense model covers: where the live map differs from its render without the
// dense pass (rendered once per cubemap, into *io_covers).
const FaceMasks &RecordingEvaluation::dense_covers(const Cubemap &p_live, const glm::dvec3 &p_probe, FaceMasks *io_covers) {
	if ((*io_covers)[0].empty()) {
		*io_covers = dense_coverage(p_live, to_cubemap(engine_tracked.render_at(p_probe, render_size, true, false).faces, size));
	}
	return *io_covers;
}

// Only at the cubemap the split is reported for: the last at or before 10 s into the sweep (the
// first, when none is; the last of a shorter recording).
bool RecordingEvaluation::splits_at(size_t p_index, double p_time_s) const {
	const double moment_s = result.start_s + SWEEP_MOMENTS_S[2] + 1e-6;
	const bool last_before = p_index + 1 == count || reader().get_ground_truth_cubemap_ref(p_index + 1).timestamp_s > moment_s;
	return (result.directions_at_s < 0.0 || p_time_s <= moment_s) && last_before;
}

void RecordingEvaluation::score_variants(double p_time_s, const Cubemap &p_truth, const Estimates &p_estimates) {
	for (int v = 0; v < variant_count; v++) {
		const Clock::time_point start = Clock::now();
		FrameScore score;
		score.timestamp_s = p_time_s;
		score.metrics = compare_cubemaps(p_estimates[v], p_truth);
		metrics_total_ms += ms_since(start);
		comparisons++;
		result.variants[v].frames.push_back(score);
		result.variants[v].last = p_estimates[v];
	}
}

// The last cubemap's maps into options.out. Every failure is kept, not only said: the caller
// reports it whether or not it shows the progress lines.
void RecordingEvaluation::write_maps(const Estimates &p_estimates, const Cubemap &p_truth) {
	std::vector<std::string> failed;
	std::error_code ec;
	std::filesystem::create_directories(options.out, ec);
	if (ec) {
		failed.push_back(options.out + ": cannot create the folder (" + ec.message() + ")");
	}
	auto write = [&](const char *p_stem, const Cubemap &p_map) {
		const std::string stem = (std::filesystem::path(options.out) / p_stem).string();
		for (const std::string &error : { write_cubemap_exr(stem + ".exr", p_map), write_cubemap_png_net(stem + ".png", p_map) }) {
			if (!error.empty()) {
				say(error);
				failed.push_back(error);
			}
		}
	};
	for (int v = 0; !ec && v < variant_count; v++) {
		write(MAP_FILES[v], p_estimates[v]);
	}
	if (!ec) {
		write(TRUTH_FILE, p_truth);
	}
	if (!failed.empty()) {
		result.out_error = failed.front() +
				(failed.size() > 1 ? " (and " + std::to_string(failed.size() - 1) + " more of the maps could not be written)" : std::string());
	}
}

} // namespace roomprobe::evaluate_detail
