#include "evaluate.h"

#include <envmap/baseline.h>
#include <envmap/dense_render.h>
#include <envmap/export.h>
#include <slam/dense_slam.h>
#include <recording/recording_reader.h>
#include <rig/fisheye_pose.h>
#include <synth/synth_renderer.h>

#include <chrono>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

namespace roomprobe {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

float srgb_to_linear(float p_v) {
	return p_v <= 0.04045f ? p_v / 12.92f : std::pow((p_v + 0.055f) / 1.055f, 2.4f);
}

// An 8-bit camera's value -> radiance: sRGB decoded, over the camera's exposure.
std::array<float, 256> linearising_lut(double p_exposure) {
	std::array<float, 256> lut{};
	for (int i = 0; i < 256; i++) {
		lut[size_t(i)] = float(srgb_to_linear(float(i) / 255.0f) / p_exposure);
	}
	return lut;
}

struct Photometry {
	bool active = false;
	double exposure = 1.0;
	cv::Mat inverse_vignetting; // CV_32FC1, fisheye-sized
	std::array<float, 256> lut{};
};

// 8-bit sRGB frame -> CV_32FC3 linear radiance (see evaluate.h).
cv::Mat linearise(const Photometry &p_photometry, const cv::Mat &p_image) {
	if (!p_photometry.active || p_image.depth() != CV_8U) {
		return p_image;
	}
	cv::Mat rgb = p_image;
	if (p_image.channels() == 1) {
		cv::cvtColor(p_image, rgb, cv::COLOR_GRAY2RGB);
	}
	cv::Mat out(rgb.size(), CV_32FC3);
	for (int y = 0; y < rgb.rows; y++) {
		const cv::Vec3b *in = rgb.ptr<cv::Vec3b>(y);
		const float *iv = p_photometry.inverse_vignetting.ptr<float>(y);
		cv::Vec3f *o = out.ptr<cv::Vec3f>(y);
		for (int x = 0; x < rgb.cols; x++) {
			for (int c = 0; c < 3; c++) {
				o[x][c] = p_photometry.lut[size_t(in[x][c])] * iv[x];
			}
		}
	}
	return out;
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

void add_timings(CoarsePipelineTimings *r_sum, const CoarsePipelineTimings &p_total, double p_scale) {
	r_sum->occlusion_ms = p_total.occlusion_ms * p_scale;
	r_sum->lighting_ms = p_total.lighting_ms * p_scale;
	r_sum->update_ms = p_total.update_ms * p_scale;
	r_sum->inpaint_ms = p_total.inpaint_ms * p_scale;
	r_sum->render_ms = p_total.render_ms * p_scale;
	r_sum->sh_ms = p_total.sh_ms * p_scale;
	r_sum->frame_ms = p_total.frame_ms * p_scale;
}

// The two dense variants of evaluate.h: the dense model fused at the true poses, drawn over the
// gain pipeline's map; and the live system, tracked, with its own coarse pipeline fed the fisheye
// poses of the tracked trajectory.
class DenseVariants {
public:
	std::string configure(const RecordingReader &p_reader, const CoarsePipelineOptions &p_coarse, bool p_linearise, double p_rgb_exposure) {
		const Rig &rig = p_reader.get_rig();
		const RoomInfo &room = p_reader.get_room();
		std::string error = with_true_poses.configure(rig.rgb, room.initial_rgb_pose);
		if (error.empty()) {
			error = tracked.configure(rig.rgb, room.initial_rgb_pose);
		}
		coarse = std::make_unique<CoarsePipeline>(p_coarse);
		if (error.empty()) {
			error = coarse->configure(rig, room.floorplan);
		}
		with_true_poses.volume().set_keep_points(room.probes);
		tracked.volume().set_keep_points(room.probes);
		use_lut = p_linearise;
		if (p_linearise) {
			lut = linearising_lut(p_rgb_exposure);
		}
		return error;
	}

	void add_rgbd(const RgbdFrame &p_frame, const Trajectory &p_truth, SlamScores *r_scores) {
		Pose truth;
		std::string error;
		const bool has_truth = p_truth.pose_at(p_frame.timestamp_s, &truth, &error);
		if (has_truth) {
			with_true_poses.process_at_pose(p_frame, truth);
		}
		const DenseSlamFrame out = tracked.process(p_frame);
		r_scores->frames++;
		r_scores->good += out.tracking.state == TrackingState::Good ? 1 : 0;
		r_scores->poor += out.tracking.state == TrackingState::Poor ? 1 : 0;
		r_scores->lost += out.tracking.state == TrackingState::Lost ? 1 : 0;
		r_scores->track_ms += out.timings.track_ms;
		r_scores->integrate_ms += out.timings.integrate_ms;
		r_scores->raycast_ms += out.timings.raycast_ms;
		if (out.tracking.state == TrackingState::Lost) {
			return;
		}
		trajectory.append({ p_frame.timestamp_s, tracked.pose() }, &error);
		if (has_truth) {
			const double e = glm::length(tracked.pose().translation - truth.translation);
			ate_sum_sq += e * e;
			ate_count++;
			r_scores->ate_max_m = std::max(r_scores->ate_max_m, e);
		}
	}

	// p_frame linearised as the other variants get it.
	void add_fisheye(const FisheyeFrame &p_frame, const Rig &p_rig) {
		Pose pose;
		std::string error;
		// The fisheye may come up to a frame after the newest RGB-D frame: extrapolate that far.
		if (fisheye_pose_at(trajectory, p_rig, p_frame.timestamp_s, &pose, &error, 0.1)) {
			coarse->add_fisheye_frame(p_frame, pose);
		}
	}

	Cubemap over_true_poses(const Cubemap &p_coarse_map, const glm::dvec3 &p_probe, const LightingChange &p_cumulative) {
		Cubemap map = clone_cubemap(p_coarse_map);
		paint(with_true_poses, light_true, p_cumulative, p_probe, &map);
		return map;
	}

	Cubemap live(const glm::dvec3 &p_probe, int p_size) {
		Cubemap map = coarse->render_cubemap(p_probe, true, p_size);
		paint(tracked, light_tracked, coarse->cumulative_lighting(), p_probe, &map);
		return map;
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
	void paint(const DenseSlam &p_slam, DenseLighting &p_lighting, const LightingChange &p_cumulative, const glm::dvec3 &p_probe, Cubemap *io_map) {
		DenseRenderOptions options;
		options.lut = use_lut ? &lut : nullptr; // null: value / 255
		render_ms += p_lighting.render_over(p_slam.volume(), p_slam.integrated_count(), p_cumulative, p_probe, options, io_map).milliseconds;
		renders++;
	}

	DenseSlam with_true_poses, tracked;
	std::unique_ptr<CoarsePipeline> coarse;
	Trajectory trajectory; // tracked, RGB-D clock
	DenseLighting light_true, light_tracked;
	std::array<float, 256> lut{};
	bool use_lut = false;
	double ate_sum_sq = 0.0;
	size_t ate_count = 0;
	double render_ms = 0.0;
	size_t renders = 0;
};

} // namespace

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
	if (!reader.has_room()) {
		result.error = p_options.recording + ": no room.yaml (the coarse model needs the floorplan)";
		return result;
	}
	if (!reader.has_ground_truth_trajectory(RecordingStream::Rgbd)) {
		result.error = p_options.recording + ": no ground-truth RGB-D trajectory (PoseSource::GroundTruth needs it)";
		return result;
	}
	if (reader.ground_truth_cubemap_count() == 0) {
		result.error = p_options.recording + ": no ground-truth cubemaps";
		return result;
	}
	const Rig &rig = reader.get_rig();
	const RoomInfo &room = reader.get_room();
	const Trajectory &trajectory = reader.ground_truth_trajectory(RecordingStream::Rgbd);

	// synth.yaml: photometry and the light switch.
	Photometry photometry;
	double rgb_exposure = 1.0;
	const std::filesystem::path synth_yaml = std::filesystem::path(p_options.recording) / "synth.yaml";
	if (std::filesystem::exists(synth_yaml)) {
		cv::FileStorage info(synth_yaml.string(), cv::FileStorage::READ);
		if (info.isOpened()) {
			if (!info["light_switch_s"].empty()) {
				result.light_switch_s = double(info["light_switch_s"]);
			}
			if (p_options.linearise) {
				photometry.active = true;
				if (!info["fisheye_exposure"].empty()) {
					photometry.exposure = double(info["fisheye_exposure"]);
				}
				if (!info["rgb_exposure"].empty()) {
					rgb_exposure = double(info["rgb_exposure"]);
				}
				double edge_gain = 1.0;
				if (!info["fisheye_vignetting_edge_gain"].empty()) {
					edge_gain = double(info["fisheye_vignetting_edge_gain"]);
				}
				photometry.lut = linearising_lut(photometry.exposure);
				photometry.inverse_vignetting.create(rig.fisheye.height, rig.fisheye.width, CV_32FC1);
				for (int y = 0; y < rig.fisheye.height; y++) {
					float *row = photometry.inverse_vignetting.ptr<float>(y);
					for (int x = 0; x < rig.fisheye.width; x++) {
						const double v = synth::fisheye_vignetting(rig.fisheye, glm::dvec2(x, y), edge_gain);
						row[x] = v > 1e-6 ? float(1.0 / v) : 0.0f;
					}
				}
			}
		}
	}
	result.linearised = photometry.active;

	// The three coarse pipelines (b and c share one) and the baseline.
	CoarsePipelineOptions base_options;
	base_options.texel_size_m = p_options.texel_size_m;
	base_options.inpaint = true;
	if (photometry.active) {
		// Thresholds in linearised units: the centre pixel's 250 / 255 and 5 / 255 (vignetting
		// correction only raises values, so saturated pixels stay above the threshold).
		base_options.lighting_options.saturated_threshold = photometry.lut[250];
		base_options.lighting_options.black_threshold = photometry.lut[5];
	}
	CoarsePipelineOptions no_light = base_options, additive = base_options, gain = base_options;
	no_light.lighting = false;
	additive.lighting = true;
	additive.lighting_model = LightingModel::ADDITIVE_PAPER;
	gain.lighting = true;
	gain.lighting_model = LightingModel::GAIN_ROBUST;
	CoarsePipeline pipe_plain(no_light), pipe_additive(additive), pipe_gain(gain);
	for (CoarsePipeline *pipe : { &pipe_plain, &pipe_additive, &pipe_gain }) {
		const std::string error = pipe->configure(rig, room.floorplan);
		if (!error.empty()) {
			result.error = p_options.recording + ": " + error;
			return result;
		}
	}

	std::unique_ptr<DenseVariants> dense;
	if (p_options.dense) {
		dense = std::make_unique<DenseVariants>();
		const std::string error = dense->configure(reader, gain, photometry.active, rgb_exposure);
		if (!error.empty()) {
			result.error = p_options.recording + ": " + error;
			return result;
		}
	}
	const int variant_count = dense ? VARIANT_COUNT : VARIANT_DENSE_TRUE_POSES;

	const GroundTruthCubemapResult first = reader.ground_truth_cubemap(0);
	if (!first.ok) {
		result.error = first.error;
		return result;
	}
	const int size = p_options.cubemap_size > 0 ? p_options.cubemap_size : first.cubemap.faces[0].cols;
	result.cubemap_size = size;
	BaselineEnvmap baseline(size);

	const char *names[VARIANT_COUNT] = { "baseline (5.3)", "coarse", "coarse+inpaint", "+light (additive)", "+light (gain)", "+dense (true poses)",
		"+dense (SLAM)" };
	result.variants.resize(size_t(variant_count));
	for (int v = 0; v < variant_count; v++) {
		result.variants[v].name = names[v];
	}

	const std::vector<PlaybackEvent> &events = reader.get_events();
	size_t next_event = 0;
	double baseline_total_ms = 0.0, metrics_total_ms = 0.0;
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
					const RgbdFrameResult rgbd = reader.read_rgbd(event.index);
					if (rgbd.ok) {
						dense->add_rgbd(rgbd.frame, trajectory, &result.slam);
					} else {
						say("skipping RGB-D frame: " + rgbd.error);
					}
				}
				continue;
			}
			const FrameRef &fref = reader.get_fisheye_ref(event.index);
			Pose pose;
			std::string pose_error;
			if (!fisheye_pose_at(trajectory, rig, fref.timestamp_s, &pose, &pose_error)) {
				say("skipping fisheye frame " + std::to_string(event.index) + ": " + pose_error);
				continue;
			}
			FisheyeFrameResult frame = reader.read_fisheye(event.index);
			if (!frame.ok) {
				say("skipping fisheye frame: " + frame.error);
				continue;
			}
			frame.frame.image = linearise(photometry, frame.frame.image);
			frame.frame.hdr = frame.frame.image.type() == CV_32FC3;
			const Clock::time_point start = Clock::now();
			baseline.add_frame(frame.frame.image, rig.fisheye, pose);
			baseline_total_ms += ms_since(start);
			pipe_plain.add_fisheye_frame(frame.frame, pose);
			pipe_additive.add_fisheye_frame(frame.frame, pose);
			pipe_gain.add_fisheye_frame(frame.frame, pose);
			if (dense) {
				dense->add_fisheye(frame.frame, rig);
			}
			result.fisheye_frames_used++;
		}
		const GroundTruthCubemapResult truth = c == 0 ? first : reader.ground_truth_cubemap(c);
		if (!truth.ok) {
			say("skipping ground-truth cubemap: " + truth.error);
			continue;
		}
		const Cubemap gt = to_cubemap(truth.cubemap.faces, size);
		const glm::dvec3 probe = truth.cubemap.position;
		Cubemap estimates[VARIANT_COUNT];
		estimates[VARIANT_BASELINE] = baseline.cubemap();
		estimates[VARIANT_COARSE] = pipe_plain.render_cubemap(probe, false, size);
		estimates[VARIANT_INPAINT] = pipe_plain.render_cubemap(probe, true, size);
		estimates[VARIANT_LIGHT_ADDITIVE] = pipe_additive.render_cubemap(probe, true, size);
		estimates[VARIANT_LIGHT_GAIN] = pipe_gain.render_cubemap(probe, true, size);
		if (dense) {
			estimates[VARIANT_DENSE_TRUE_POSES] = dense->over_true_poses(estimates[VARIANT_LIGHT_GAIN], probe, pipe_gain.cumulative_lighting());
			estimates[VARIANT_DENSE_SLAM] = dense->live(probe, size);
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
			std::filesystem::create_directories(p_options.out);
			const char *files[VARIANT_COUNT] = { "baseline", "coarse", "coarse_inpaint", "coarse_light_additive", "coarse_light_gain", "dense_true_poses",
				"dense_slam" };
			for (int v = 0; v < variant_count; v++) {
				const std::string stem = (std::filesystem::path(p_options.out) / files[v]).string();
				std::string error = write_cubemap_exr(stem + ".exr", estimates[v]);
				if (error.empty()) {
					error = write_cubemap_png_net(stem + ".png", estimates[v]);
				}
				if (!error.empty()) {
					say(error);
				}
			}
			const std::string stem = (std::filesystem::path(p_options.out) / "ground_truth").string();
			write_cubemap_exr(stem + ".exr", gt);
			write_cubemap_png_net(stem + ".png", gt);
		}
	}
	if (result.cubemaps == 0) {
		result.error = p_options.recording + ": no ground-truth cubemap could be evaluated";
		return result;
	}
	for (VariantScores &v : result.variants) {
		double after_psnr = 0.0, after_ssim = 0.0;
		for (const FrameScore &f : v.frames) {
			v.mean_psnr_db += f.metrics.psnr_db;
			v.mean_ssim += f.metrics.ssim;
			v.mean_psnr_linear_db += f.metrics.psnr_linear_db;
			v.mean_ssim_linear += f.metrics.ssim_linear;
			if (result.light_switch_s >= 0.0 && f.timestamp_s > result.light_switch_s) {
				v.after_switch_frames++;
				after_psnr += f.metrics.psnr_db;
				after_ssim += f.metrics.ssim;
			}
		}
		const double n = double(v.frames.size());
		v.mean_psnr_db /= n;
		v.mean_ssim /= n;
		v.mean_psnr_linear_db /= n;
		v.mean_ssim_linear /= n;
		if (v.after_switch_frames > 0) {
			v.after_switch_psnr_db = after_psnr / double(v.after_switch_frames);
			v.after_switch_ssim = after_ssim / double(v.after_switch_frames);
		}
	}
	const double per_frame = result.fisheye_frames_used > 0 ? 1.0 / double(result.fisheye_frames_used) : 0.0;
	add_timings(&result.timings_inpaint, pipe_plain.total_timings(), per_frame);
	add_timings(&result.timings_additive, pipe_additive.total_timings(), per_frame);
	add_timings(&result.timings_gain, pipe_gain.total_timings(), per_frame);
	// Renders: two per cubemap for the plain pipeline, one for the others.
	const double per_cubemap = 1.0 / double(result.cubemaps);
	result.timings_inpaint.render_ms = pipe_plain.total_timings().render_ms * per_cubemap * 0.5;
	result.timings_additive.render_ms = pipe_additive.total_timings().render_ms * per_cubemap;
	result.timings_gain.render_ms = pipe_gain.total_timings().render_ms * per_cubemap;
	result.baseline_ms = baseline_total_ms * per_frame;
	result.metrics_ms = comparisons > 0 ? metrics_total_ms / double(comparisons) : 0.0;
	if (dense) {
		dense->finish(&result.slam);
	}
	result.ok = true;
	return result;
}

std::string format_evaluation(const EvaluationResult &p_result, bool p_per_frame) {
	std::ostringstream out;
	char line[256];
	if (!p_result.ok) {
		return "evaluation failed: " + p_result.error + "\n";
	}
	if (p_per_frame) {
		out << "per frame: t [s], then PSNR [dB] / SSIM of each variant\n";
		const size_t n = p_result.variants[0].frames.size();
		for (size_t i = 0; i < n; i++) {
			std::snprintf(line, sizeof(line), "%8.3f", p_result.variants[0].frames[i].timestamp_s);
			out << line;
			for (const VariantScores &v : p_result.variants) {
				std::snprintf(line, sizeof(line), "  %6.2f/%.4f", v.frames[i].metrics.psnr_db, v.frames[i].metrics.ssim);
				out << line;
			}
			out << "\n";
		}
	}
	std::snprintf(line, sizeof(line), "%zu cubemaps (%d px faces), %zu fisheye frames, poses: ground truth, frames %s\n", p_result.cubemaps,
			p_result.cubemap_size, p_result.fisheye_frames_used, p_result.linearised ? "linearised (synth.yaml)" : "as recorded");
	out << line;
	std::snprintf(line, sizeof(line), "%-20s %10s %8s %12s %10s\n", "variant", "PSNR[dB]", "SSIM", "PSNRlin[dB]", "SSIMlin");
	out << line;
	for (const VariantScores &v : p_result.variants) {
		std::snprintf(line, sizeof(line), "%-20s %10.2f %8.4f %12.2f %10.4f\n", v.name.c_str(), v.mean_psnr_db, v.mean_ssim, v.mean_psnr_linear_db,
				v.mean_ssim_linear);
		out << line;
	}
	if (p_result.light_switch_s >= 0.0) {
		std::snprintf(line, sizeof(line), "after the light switch (t > %.3f s, cubemap metrics, %zu frames):\n", p_result.light_switch_s,
				p_result.variants[0].after_switch_frames);
		out << line;
		for (const VariantScores &v : p_result.variants) {
			std::snprintf(line, sizeof(line), "%-20s %10.2f %8.4f\n", v.name.c_str(), v.after_switch_psnr_db, v.after_switch_ssim);
			out << line;
		}
	}
	out << "per-stage timings, ms per fisheye frame (render: per cubemap):\n";
	std::snprintf(line, sizeof(line), "%-20s %9s %9s %9s %9s %9s %9s\n", "pipeline", "occlusion", "lighting", "update", "inpaint", "frame", "render");
	out << line;
	const std::pair<const char *, const CoarsePipelineTimings *> rows[] = { { "inpaint, no light", &p_result.timings_inpaint },
		{ "light (additive)", &p_result.timings_additive }, { "light (gain)", &p_result.timings_gain } };
	for (const auto &[name, t] : rows) {
		std::snprintf(line, sizeof(line), "%-20s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f\n", name, t->occlusion_ms, t->lighting_ms, t->update_ms,
				t->inpaint_ms, t->frame_ms, t->render_ms);
		out << line;
	}
	std::snprintf(line, sizeof(line), "baseline add_frame %.2f ms per frame; metrics %.2f ms per comparison\n", p_result.baseline_ms, p_result.metrics_ms);
	out << line;
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
