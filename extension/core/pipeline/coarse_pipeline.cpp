#include "coarse_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/geometric.hpp>

namespace roomprobe {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

} // namespace

CoarsePipeline::CoarsePipeline(const CoarsePipelineOptions &p_options) :
		opts(p_options) {
	opts.update.policy = TextureUpdatePolicy::Best;
	opts.lighting_options.model = opts.lighting_model;
}

CoarsePipeline::~CoarsePipeline() = default;

std::string CoarsePipeline::configure(const OmniParams &p_fisheye, const Floorplan &p_floorplan) {
	configured = false;
	inpainter.reset();
	renderer.reset();
	RoomMeshOptions mesh_options;
	mesh_options.texel_size_m = opts.texel_size_m;
	RoomMeshResult built = build_room_mesh(p_floorplan, mesh_options);
	if (!built.ok) {
		return "coarse pipeline: room mesh: " + built.error;
	}
	has_fisheye = p_fisheye.width != 0 || p_fisheye.height != 0;
	if (has_fisheye && (p_fisheye.width <= 0 || p_fisheye.height <= 0)) {
		return "coarse pipeline: fisheye has no size";
	}
	fisheye = p_fisheye;
	floorplan = p_floorplan;
	room = std::move(built.mesh);
	geometry = make_texel_geometry(room);
	coarse = make_coarse_texture(room);
	completed.release();
	inpainted.release();
	convex = opts.occlusion.skip_convex && floorplan_is_convex(floorplan);
	renderer = std::make_unique<CoarseCubemapRenderer>(room);
	inpainter = std::make_unique<TextureInpainter>(room, opts.inpainting);
	frames = 0;
	cumulative = LightingChange();
	cumulative.valid = true;
	last = CoarsePipelineTimings();
	total = CoarsePipelineTimings();
	configured = true;
	return "";
}

RgbTextureStats CoarsePipeline::add_rgb_frame(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut) {
	if (!configured || !(opts.rgb_texture || !has_fisheye)) {
		return RgbTextureStats();
	}
	return rgb_update(p_frame, p_camera, p_world_from_rgb, p_lut, nullptr);
}

RgbTextureStats CoarsePipeline::rgb_update(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut,
		LightingPairs *r_pairs) {
	const Clock::time_point start = Clock::now();
	if (rgb_fresh.size() != coarse.color.size()) {
		rgb_fresh = cv::Mat(coarse.color.size(), CV_8UC1, cv::Scalar(0));
	}
	const RgbTextureStats stats =
			update_coarse_texture_from_rgb(geometry, p_camera, p_world_from_rgb, p_frame.rgb, p_frame.depth_m, p_lut, &coarse, opts.rgb, &rgb_fresh, r_pairs);
	last.rgb_ms = ms_since(start);
	total.rgb_ms += last.rgb_ms;
	return stats;
}

CoarseFrameStats CoarsePipeline::add_fisheye_frame(const FisheyeFrame &p_frame, const Pose &p_world_from_fisheye) {
	CoarseFrameStats stats;
	if (!configured || !has_fisheye) {
		return stats;
	}
	const Clock::time_point frame_start = Clock::now();
	CoarsePipelineTimings t;

	// Every texel's pixel, projected once (the tiles the fisheye cannot see skipped): for the
	// occlusion mask's tiles and the update (counted with the update).
	Clock::time_point start = Clock::now();
	project_texels(geometry, fisheye, p_world_from_fisheye, &projection);
	t.update_ms = ms_since(start);

	// 1. Occlusion (§4.4).
	start = Clock::now();
	stats.occlusion_skipped = convex;
	if (!convex) {
		occlusion_mask(room, geometry, p_world_from_fisheye.translation, projection, &mask, opts.occlusion);
	}
	const cv::Mat *mask_ptr = convex ? nullptr : &mask;
	t.occlusion_ms = ms_since(start);

	// 2. Texture update (§4.3, keep the best); it also gathers the lighting estimate's (old
	// texel, new sample) pairs before it writes.
	start = Clock::now();
	const bool estimate_lighting = opts.lighting && frames > 0;
	lighting_pairs.step = opts.lighting_options.sample_step;
	stats.update = update_coarse_texture(room, geometry, projection, fisheye, p_world_from_fisheye, p_frame.image, mask_ptr, &coarse, opts.update,
			estimate_lighting ? &lighting_pairs : nullptr, p_frame.saturated.empty() ? nullptr : &p_frame.saturated);
	if (!rgb_fresh.empty()) {
		// The RGB camera's values since the last frame are of the present lighting too.
		cv::bitwise_or(coarse.updated, rgb_fresh, coarse.updated);
		rgb_fresh.setTo(cv::Scalar(0));
	}
	t.update_ms += ms_since(start);

	// 3. Lighting change (§4.6) from those pairs, applied to the observed texels this frame did not
	// update (the update's order does not matter: the pairs hold the values from before it).
	change_lighting(estimate_lighting, &stats, &t);

	finish_frame(&t, &stats, ms_since(frame_start));
	return stats;
}

CoarseFrameStats CoarsePipeline::add_rgb_view(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut) {
	CoarseFrameStats stats;
	if (!configured || has_fisheye) {
		return stats;
	}
	const Clock::time_point frame_start = Clock::now();
	const bool estimate_lighting = opts.lighting && frames > 0;
	lighting_pairs.step = opts.lighting_options.sample_step;
	const RgbTextureStats rgb = rgb_update(p_frame, p_camera, p_world_from_rgb, p_lut, estimate_lighting ? &lighting_pairs : nullptr);
	stats.update.texels_visible = rgb.texels_visible;
	stats.update.texels_updated = rgb.texels_updated;
	// The update's mask of this view's texels, as the fisheye's update leaves it.
	rgb_fresh.copyTo(coarse.updated);
	rgb_fresh.setTo(cv::Scalar(0));
	CoarsePipelineTimings t;
	t.update_ms = last.rgb_ms;
	// The lighting change (§4.6) from the pairs of texels seen again, as with the fisheye.
	change_lighting(estimate_lighting, &stats, &t);
	finish_frame(&t, &stats, ms_since(frame_start));
	return stats;
}

void CoarsePipeline::change_lighting(bool p_estimate, CoarseFrameStats *io_stats, CoarsePipelineTimings *io_timings) {
	const Clock::time_point start = Clock::now();
	if (p_estimate) {
		io_stats->lighting = estimate_lighting_change(lighting_pairs.gather(), opts.lighting_options);
	}
	if (io_stats->lighting.valid) {
		apply_lighting_change(&coarse, io_stats->lighting, &geometry.points);
		cumulative = compose_lighting(io_stats->lighting, cumulative);
	}
	io_timings->lighting_ms = ms_since(start);
}

void CoarsePipeline::finish_frame(CoarsePipelineTimings *io_timings, CoarseFrameStats *io_stats, double p_frame_start_ms_ago) {
	CoarsePipelineTimings &t = *io_timings;
	// 4. Inpainting (§4.5), here or on the worker.
	const Clock::time_point start = Clock::now();
	if (opts.inpaint && opts.inpaint_async) {
		inpainter->request(coarse);
		inpainter->try_take_result(&inpainted, nullptr, &io_stats->inpaint);
		compose_completed();
	} else if (opts.inpaint) {
		completed = inpainter->inpaint(coarse, &io_stats->inpaint);
	}
	t.inpaint_ms = ms_since(start);

	frames++;
	t.frame_ms = p_frame_start_ms_ago + t.inpaint_ms;
	t.render_ms = last.render_ms;
	t.sh_ms = last.sh_ms;
	t.rgb_ms = last.rgb_ms; // add_rgb_frame's, kept
	last = t;
	total.occlusion_ms += t.occlusion_ms;
	total.lighting_ms += t.lighting_ms;
	total.update_ms += t.update_ms;
	total.inpaint_ms += t.inpaint_ms;
	total.frame_ms += t.frame_ms;
}

void CoarsePipeline::compose_completed() {
	if (inpainted.empty() || inpainted.size() != coarse.color.size() || inpainted.type() != coarse.color.type()) {
		coarse.color.copyTo(completed);
		return;
	}
	// The observed colour where there is one, else the fill: one pass, no mask made. Serial: the
	// inpainting worker is busy on the other core while this runs.
	completed.create(coarse.color.size(), coarse.color.type());
	for (int y = 0; y < coarse.color.rows; y++) {
		const cv::Vec3f *color_row = coarse.color.ptr<cv::Vec3f>(y);
		const cv::Vec3f *fill_row = inpainted.ptr<cv::Vec3f>(y);
		const uint8_t *observed_row = coarse.observed.ptr<uint8_t>(y);
		cv::Vec3f *out_row = completed.ptr<cv::Vec3f>(y);
		for (int x = 0; x < coarse.color.cols; x++) {
			out_row[x] = observed_row[x] != 0 ? color_row[x] : fill_row[x];
		}
	}
}

void CoarsePipeline::finish_inpainting() {
	if (!configured || !opts.inpaint || !opts.inpaint_async || frames == 0) {
		return;
	}
	inpainter->wait_idle();
	inpainter->try_take_result(&inpainted);
	compose_completed();
}

double CoarsePipeline::carry_texture(const CoarsePipeline &p_old, const Pose &p_new_from_old, double p_tolerance_m) {
	if (!configured || !p_old.configured || geometry.surface_texels == 0) {
		return 0.0;
	}
	const Pose old_from_new = inverse(p_new_from_old);
	// Each texel looks for the old surface along its normal, from this far inside the room.
	const double reach_m = 4.0 * std::max(p_tolerance_m, 0.01);
	const double same_direction = std::cos(10.0 * M_PI / 180.0);
	const CoarseTexture &from = p_old.coarse;
	size_t carried = 0; // texels that took an observation (fisheye or RGB)
	for (int y = 0; y < geometry.height; y++) {
		for (int x = 0; x < geometry.width; x++) {
			const size_t i = size_t(y) * size_t(geometry.width) + size_t(x);
			if (geometry.charts[i] < 0) {
				continue;
			}
			const glm::dvec3 point = transform_point(old_from_new, geometry.points[i]);
			const glm::dvec3 normal = old_from_new.rotation * geometry.normals[i];
			RoomRayHit hit;
			if (!intersect_room(p_old.room, point + normal * reach_m, -normal, &hit) || std::abs(hit.distance - reach_m) > p_tolerance_m) {
				continue;
			}
			const Chart &old_chart = p_old.room.charts[size_t(hit.chart)];
			const Chart &new_chart = room.charts[size_t(geometry.charts[i])];
			const glm::dvec3 old_normal(old_chart.normal.x, old_chart.normal.y, old_chart.normal.z);
			if (old_chart.kind != new_chart.kind || glm::dot(old_normal, normal) < same_direction) {
				continue;
			}
			const int ox = std::clamp(int(std::floor(hit.atlas.x)), 0, p_old.geometry.width - 1);
			const int oy = std::clamp(int(std::floor(hit.atlas.y)), 0, p_old.geometry.height - 1);
			if (!p_old.geometry.on_surface(ox, oy)) {
				continue;
			}
			coarse.color.at<cv::Vec3f>(y, x) = from.color.at<cv::Vec3f>(oy, ox);
			coarse.observed.at<uint8_t>(y, x) = from.observed.at<uint8_t>(oy, ox);
			coarse.quality.at<float>(y, x) = from.quality.at<float>(oy, ox);
			coarse.saturated.at<uint8_t>(y, x) = from.saturated.at<uint8_t>(oy, ox);
			coarse.rgb_quality.at<float>(y, x) = from.rgb_quality.at<float>(oy, ox);
			carried += from.observed.at<uint8_t>(oy, ox) != 0 || from.rgb_quality.at<float>(oy, ox) > 0.0f ? 1 : 0;
		}
	}
	if (carried > 0) {
		frames = p_old.frames;
		cumulative = p_old.cumulative;
		inpainted.release(); // of the old layout
		compose_completed();
	}
	return double(carried) / double(geometry.surface_texels);
}

const cv::Mat &CoarsePipeline::completed_color() const {
	return (opts.inpaint && !completed.empty()) ? completed : coarse.color;
}

Cubemap CoarsePipeline::render_cubemap(const glm::dvec3 &p_position, bool p_completed, int p_size) {
	if (!configured) {
		return Cubemap();
	}
	const Clock::time_point start = Clock::now();
	const cv::Mat &atlas = p_completed ? completed_color() : coarse.color;
	Cubemap map = renderer->render(atlas, p_position, p_size > 0 ? p_size : opts.cubemap_size);
	last.render_ms = ms_since(start);
	total.render_ms += last.render_ms;
	return map;
}

ShCoefficients CoarsePipeline::sh(const glm::dvec3 &p_position) {
	const Cubemap map = render_cubemap(p_position, true);
	const Clock::time_point start = Clock::now();
	const ShCoefficients coefficients = project_sh(map);
	last.sh_ms = ms_since(start);
	total.sh_ms += last.sh_ms;
	return coefficients;
}

} // namespace roomprobe
