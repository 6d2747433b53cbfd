// The reports of evaluate.h as text: the evaluation's summary table, timings and direction split,
// and the error budget's table.

#include "evaluate.h"

#include <cstdio>
#include <iterator>
#include <sstream>

namespace roomprobe {

namespace {

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

// One line per frame: its time, then each variant's PSNR / SSIM / irradiance error.
void format_per_frame(const EvaluationResult &p_result, std::ostringstream &r_out) {
	char line[256];
	r_out << "per frame: t [s], then PSNR [dB] / SSIM / irradiance error [%] of each variant\n";
	const size_t n = p_result.variants[0].frames.size();
	for (size_t i = 0; i < n; i++) {
		std::snprintf(line, sizeof(line), "%8.3f", p_result.variants[0].frames[i].timestamp_s);
		r_out << line;
		for (const VariantScores &v : p_result.variants) {
			std::snprintf(line, sizeof(line), "  %6.2f/%.4f/%.1f", v.frames[i].metrics.psnr_db, v.frames[i].metrics.ssim, 100.0 * v.frames[i].metrics.irradiance_error);
			r_out << line;
		}
		r_out << "\n";
	}
}

// Each variant at SWEEP_MOMENTS_S into the sweep.
void format_moments(const EvaluationResult &p_result, std::ostringstream &r_out) {
	char line[256];
	r_out << "into the sweep (the last cubemap at or before each moment): PSNR / PSNRmu / worst 5 % [dB], Eirr [%]\n";
	std::snprintf(line, sizeof(line), "%-27s", "variant");
	r_out << line;
	for (double moment : SWEEP_MOMENTS_S) {
		std::snprintf(line, sizeof(line), " %27s", ("at " + std::to_string(int(moment)) + " s").c_str());
		r_out << line;
	}
	r_out << "\n";
	for (const VariantScores &v : p_result.variants) {
		std::snprintf(line, sizeof(line), "%-27s", v.name.c_str());
		r_out << line;
		for (int m = 0; m < 3; m++) {
			if (v.at_moment[m] < 0) {
				std::snprintf(line, sizeof(line), " %27s", "(recording too short)");
			} else {
				const CubemapMetrics &f = v.frames[size_t(v.at_moment[m])].metrics;
				std::snprintf(line, sizeof(line), " %5.2f/%5.2f/%5.2f, %6.2f%%", f.psnr_db, f.psnr_mu_db, f.psnr_worst5_db, 100.0 * f.irradiance_error);
			}
			r_out << line;
		}
		r_out << "\n";
	}
}

} // namespace

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
		format_per_frame(p_result, out);
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
	format_moments(p_result, out);
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
		out << "backend (+dense (SLAM)): " << p_result.compute << "\n";
	}
	return out.str();
}

} // namespace roomprobe
