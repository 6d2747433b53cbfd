#include "dense_slam.h"

#include "depth_pyramid.h"

#include "icp_reduce_gpu.h"

#include <parallel/parallel_for.h>

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <limits>
#include <numbers>
#include <vector>

namespace roomprobe {

namespace {

// Per pixel of an image 1 / 2^p_level the size of p_depth_m, the camera-z interval spanned by the
// readings of its 2^level x 2^level block, widened by p_margin_m (CV_32FC2; NaN where the block
// has no reading).
cv::Mat search_intervals(const cv::Mat &p_depth_m, int p_level, float p_margin_m) {
	const int side = 1 << p_level;
	const float nan = std::numeric_limits<float>::quiet_NaN();
	cv::Mat intervals(p_depth_m.rows >> p_level, p_depth_m.cols >> p_level, CV_32FC2);
	parallel_for(cv::Range(0, intervals.rows), [&](const cv::Range &p_range) {
		for (int v = p_range.start; v < p_range.end; v++) {
			cv::Vec2f *out = intervals.ptr<cv::Vec2f>(v);
			for (int u = 0; u < intervals.cols; u++) {
				float lo = std::numeric_limits<float>::infinity(), hi = -lo;
				for (int y = v * side; y < (v + 1) * side; y++) {
					const float *row = p_depth_m.ptr<float>(y);
					for (int x = u * side; x < (u + 1) * side; x++) {
						if (row[x] > 0.0f) { // false for NaN
							lo = std::min(lo, row[x]);
							hi = std::max(hi, row[x]);
						}
					}
				}
				out[u] = lo <= hi ? cv::Vec2f(lo - p_margin_m, hi + p_margin_m) : cv::Vec2f(nan, nan);
			}
		}
	});
	return intervals;
}

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

bool has_model(const ModelMaps &p_maps) {
	return !p_maps.points.empty();
}

// The last inter-frame motion p_delta (taken over p_last_dt_s) carried over p_dt_s at constant
// velocity. Frames at a steady rate keep p_delta exactly; when frames were dropped (the live
// engine's SLAM worker takes only the newest) the motion is scaled, so the guess stays near.
Pose motion_over(const Pose &p_delta, double p_dt_s, double p_last_dt_s) {
	const double k = p_last_dt_s > 0.0 && p_dt_s > 0.0 ? p_dt_s / p_last_dt_s : 1.0;
	if (std::abs(k - 1.0) < 0.25 || !std::isfinite(k)) {
		return p_delta;
	}
	const double scale = std::min(k, 10.0);
	Pose out;
	out.translation = p_delta.translation * scale;
	const double angle = glm::angle(p_delta.rotation);
	out.rotation = angle > 1e-12 ? glm::angleAxis(angle * scale, glm::axis(p_delta.rotation)) : p_delta.rotation;
	return out;
}

} // namespace

std::string DenseSlam::faster_than_a_hand(const TrackingResult &p_tracking, double p_time_s) const {
	return faster_than_a_hand(p_tracking, p_time_s, last_pose, last_time_s);
}

std::string DenseSlam::faster_than_a_hand(const TrackingResult &p_tracking, double p_time_s, const Pose &p_from, double p_from_time_s) const {
	if (p_tracking.state == TrackingState::Lost || integrated_frames == 0 || !(opts.max_speed_m_s > 0.0)) {
		return "";
	}
	const double dt_s = std::clamp(p_time_s - p_from_time_s, 0.0, 1.0);
	const double moved_m = translation_difference_m(p_tracking.world_from_camera, p_from);
	if (!(moved_m > opts.max_speed_m_s * dt_s + 0.02)) {
		return "";
	}
	return "the pose moved " + std::to_string(moved_m) + " m in " + std::to_string(dt_s) + " s since the last tracked pose, faster than " +
			std::to_string(opts.max_speed_m_s) + " m/s: a slide along surfaces that do not fix the pose, not the rig";
}

DenseSlam::DenseSlam(const DenseSlamOptions &p_options) :
		opts(p_options), tracker(p_options.icp), tsdf(p_options.tsdf), keyframes(p_options.keyframes) {}

std::string DenseSlam::set_compute(std::shared_ptr<ComputeDevice> p_device) {
	compute_error.clear();
	if (!p_device) {
		tracker.set_gpu(nullptr);
		tsdf.set_compute(nullptr);
		return "";
	}
	std::string error;
	std::shared_ptr<IcpReducerGpu> reducer = IcpReducerGpu::create(p_device, &error);
	tracker.set_gpu(reducer);
	compute_error = reducer ? "" : "tracking on the CPU (ICP on the GPU: " + error + ")";
	const std::string volume = tsdf.set_compute(std::move(p_device));
	if (!volume.empty()) {
		compute_error += std::string(compute_error.empty() ? "" : "; ") + volume;
	}
	return compute_error;
}

std::string DenseSlam::compute_problem() const {
	if (!compute_error.empty()) {
		return compute_error;
	}
	std::string out;
	if (!tracker.compute_problem().empty()) {
		out = "tracking on the CPU (" + tracker.compute_problem() + ")";
	}
	const std::string volume = tsdf.compute_problem();
	if (!volume.empty()) {
		out += std::string(out.empty() ? "" : "; ") + volume;
	}
	return out;
}

std::string DenseSlam::configure(const PinholeParams &p_camera, const Pose &p_initial_world_from_camera) {
	configured = false;
	if (p_camera.width <= 0 || p_camera.height <= 0 || !(p_camera.fx > 0.0) || !(p_camera.fy > 0.0)) {
		return "dense SLAM: the RGB-D camera needs a positive size and focal length";
	}
	if (!is_finite(p_initial_world_from_camera)) {
		return "dense SLAM: the initial pose is not finite";
	}
	params = p_camera;
	intrinsics = pinhole_intrinsics(p_camera);
	undistort_map_x.release();
	undistort_map_y.release();
	if (has_pinhole_distortion(p_camera)) {
		// Kernels use the distortion-free model: undo the distortion once per frame, by table.
		const cv::Mat k = (cv::Mat_<double>(3, 3) << p_camera.fx, 0.0, p_camera.cx, 0.0, p_camera.fy, p_camera.cy, 0.0, 0.0, 1.0);
		const cv::Mat d = (cv::Mat_<double>(1, 5) << p_camera.k1, p_camera.k2, p_camera.p1, p_camera.p2, p_camera.k3);
		cv::initUndistortRectifyMap(k, d, cv::Mat(), k, cv::Size(p_camera.width, p_camera.height), CV_32FC1, undistort_map_x, undistort_map_y);
	}
	tsdf.reset();
	tsdf.take_dirty_blocks(); // a fresh model: nothing of the old one is re-meshed
	keyframes.clear();
	candidate = KeyframeCandidate();
	keyframe_total = 0;
	keyframe_relocalised = 0;
	reference = ModelMaps();
	last_pose = p_initial_world_from_camera;
	has_previous = false;
	last_state = TrackingState::Lost;
	last_colour_held = false;
	frames = 0;
	integrated_frames = 0;
	relocalise_attempts = 0;
	relocalised_frames = 0;
	configured = true;
	return "";
}

std::string DenseSlam::check_frame(const RgbdFrame &p_frame) const {
	if (p_frame.depth_m.type() != CV_32FC1 || p_frame.depth_m.cols != params.width || p_frame.depth_m.rows != params.height ||
			(!p_frame.rgb.empty() && (p_frame.rgb.type() != CV_8UC3 || p_frame.rgb.size() != p_frame.depth_m.size()))) {
		return "the frame does not fit the camera: depth must be CV_32FC1 and rgb CV_8UC3, both " + std::to_string(params.width) + "x" +
				std::to_string(params.height);
	}
	return "";
}

DenseSlamFrame DenseSlam::process_at_pose(const RgbdFrame &p_frame, const Pose &p_world_from_camera) {
	DenseSlamFrame out;
	out.tracking.world_from_camera = p_world_from_camera;
	out.tracking.reason = configured ? check_frame(p_frame) : "dense SLAM is not configured";
	if (!out.tracking.reason.empty()) {
		return out;
	}
	const Clock::time_point start = Clock::now();
	cv::Mat depth, rgb;
	undistort(p_frame, &depth, &rgb);
	out.tracking.state = TrackingState::Good;
	out.integration = integrate(depth, rgb, p_world_from_camera);
	out.integrated = true;
	previous_pose = last_pose;
	last_pose = p_world_from_camera;
	last_state = TrackingState::Good;
	frames++;
	integrated_frames++;
	out.timings.integrate_ms = ms_since(start);
	out.timings.frame_ms = out.timings.integrate_ms;
	return out;
}

void DenseSlam::undistort(const RgbdFrame &p_frame, cv::Mat *r_depth, cv::Mat *r_rgb) const {
	if (undistort_map_x.empty()) {
		*r_depth = p_frame.depth_m;
		*r_rgb = p_frame.rgb;
		return;
	}
	// Nearest for depth: interpolating across a depth edge invents surfaces.
	cv::remap(p_frame.depth_m, *r_depth, undistort_map_x, undistort_map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
	cv::remap(p_frame.rgb, *r_rgb, undistort_map_x, undistort_map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
}

TrackingResult DenseSlam::track(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_initial_world_from_camera) const {
	return track_with(tracker, p_depth_m, p_rgb, p_initial_world_from_camera);
}

TrackingResult DenseSlam::track_with(const IcpTracker &p_tracker, const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_initial_world_from_camera) const {
	if (!has_model(reference)) {
		TrackingResult lost;
		lost.state = TrackingState::Lost;
		lost.reason = "no model to track against yet";
		lost.world_from_camera = p_initial_world_from_camera;
		return lost;
	}
	return track_against(p_tracker, reference, p_depth_m, p_rgb, p_initial_world_from_camera);
}

TrackingResult DenseSlam::track_against(const IcpTracker &p_tracker, const ModelMaps &p_model, const cv::Mat &p_depth_m, const cv::Mat &p_rgb,
		const Pose &p_initial_world_from_camera) const {
	cv::Mat depth = p_depth_m, rgb = p_rgb;
	PinholeIntrinsics camera = intrinsics;
	for (int level = 0; level < opts.tracking_level; level++) {
		depth = downsample_depth(clean_depth(depth, float(opts.icp.min_depth_m), float(opts.icp.max_depth_m)), float(opts.icp.pyramid_band_m));
		if (!rgb.empty()) {
			cv::resize(rgb, rgb, depth.size(), 0.0, 0.0, cv::INTER_AREA);
		}
		camera = camera.level(1);
	}
	if (integrated_frames < size_t(std::max(0, opts.young_model_frames)) && opts.young_model_noise_factor > 0.0) {
		IcpTracker young = p_tracker; // its device too
		IcpOptions held = p_tracker.get_options();
		held.hold_constraint = std::max(held.hold_constraint, opts.young_model_noise_factor * normal_spread(p_model.normals));
		young.set_options(held);
		return young.track(depth, rgb, camera, p_model, p_initial_world_from_camera);
	}
	return p_tracker.track(depth, rgb, camera, p_model, p_initial_world_from_camera);
}

ModelMaps DenseSlam::reference_at(const Pose &p_pose) const {
	ModelMaps maps;
	cast_reference(p_pose, nullptr, &maps);
	return maps;
}

void DenseSlam::cast_reference(const Pose &p_pose, const cv::Mat *p_search_m, ModelMaps *r_maps) const {
	const PinholeIntrinsics camera = intrinsics.level(std::clamp(opts.raycast_level, 0, 4));
	const bool gradient_normals = !opts.reference_normals_from_points;
	if (p_search_m != nullptr) {
		tsdf.raycast(camera, p_pose, *p_search_m, r_maps, nullptr, gradient_normals);
	} else {
		tsdf.raycast(camera, p_pose, tsdf.options().min_depth_m, tsdf.options().max_depth_m, r_maps, nullptr, gradient_normals);
	}
	if (!gradient_normals) {
		model_normals_from_points(r_maps, float(opts.icp.surface.max_jump_relative));
	}
}

IntegrationStats DenseSlam::integrate(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_world_from_camera) {
	const std::unique_lock<std::shared_mutex> writing(volume_mutex);
	return tsdf.integrate(p_depth_m, p_rgb, intrinsics, p_world_from_camera);
}

void DenseSlam::raycast(const Pose &p_world_from_camera, ModelMaps *r_maps) const {
	tsdf.raycast(intrinsics, p_world_from_camera, r_maps);
}

TsdfBlockCopy DenseSlam::copy_changed_blocks(std::vector<TsdfVoxel> p_storage) {
	return TsdfBlockCopy(tsdf, tsdf.take_dirty_blocks(), std::move(p_storage));
}

DenseSlamFrame DenseSlam::process(const RgbdFrame &p_frame) {
	DenseSlamFrame out;
	if (!configured) {
		out.tracking.reason = "dense SLAM is not configured";
		return out;
	}
	const Clock::time_point frame_start = Clock::now();
	out.tracking.reason = check_frame(p_frame);
	if (!out.tracking.reason.empty()) {
		out.tracking.world_from_camera = last_pose;
		last_state = out.tracking.state;
		last_colour_held = false;
		frames++;
		return out;
	}
	Clock::time_point start = Clock::now();
	cv::Mat depth, rgb;
	undistort(p_frame, &depth, &rgb);
	out.timings.undistort_ms = ms_since(start);

	start = Clock::now();
	if (!has_model(reference) && integrated_frames == 0) {
		// The first frame defines the model at the initial pose; it needs readings all the same.
		const int valid = cv::countNonZero((depth == depth) & (depth > 0.0f)); // NaN != NaN
		const bool enough = valid >= int(opts.icp.min_valid_fraction * double(depth.total()));
		out.tracking.world_from_camera = last_pose;
		out.tracking.state = enough ? TrackingState::Good : TrackingState::Lost;
		out.tracking.reason = enough ? "" : "too few valid depth pixels for the first frame: " + std::to_string(valid) + " of " + std::to_string(depth.total());
	} else {
		// Constant velocity while trusted; the held pose when re-tracking after a loss.
		Pose guess = last_pose;
		// A frame whose colour slide was held keeps the velocity: its free direction is the guess's.
		if (opts.constant_velocity && has_previous && (last_state == TrackingState::Good || last_colour_held)) {
			guess = compose(last_pose, motion_over(compose(inverse(previous_pose), last_pose), p_frame.timestamp_s - last_time_s, last_time_s - previous_time_s));
		}
		out.tracking = track(depth, rgb, guess);
		const std::string too_fast = faster_than_a_hand(out.tracking, p_frame.timestamp_s);
		if (!too_fast.empty()) {
			out.tracking.state = TrackingState::Lost;
			out.tracking.reason = too_fast;
		}
		if (out.tracking.state == TrackingState::Lost && opts.relocalise && has_model(reference)) {
			relocalise_attempts++;
			TrackingResult found = relocalise(depth, rgb);
			const std::string found_too_fast = faster_than_a_hand(found, p_frame.timestamp_s);
			if (found.state == TrackingState::Good && found_too_fast.empty()) {
				out.tracking = found;
				relocalised_frames++;
			} else {
				out.tracking.reason += "; " + (found_too_fast.empty() ? found.reason : "relocalised, but " + found_too_fast);
				// Anywhere the keyframes saw: no speed limit, since the camera may have been carried.
				const TrackingResult far = opts.relocalise_globally ? relocalise_far(depth, rgb, p_frame.timestamp_s) : TrackingResult();
				if (far.state == TrackingState::Good) {
					out.tracking = far;
					relocalised_frames++;
					keyframe_relocalised++;
				} else if (opts.relocalise_globally) {
					out.tracking.reason += "; " + far.reason;
				}
			}
		}
		if (out.tracking.state == TrackingState::Lost) {
			out.tracking.world_from_camera = last_pose;
		}
	}
	out.timings.track_ms = ms_since(start);

	// A Poor pose still moves the camera (the AR view follows it); only Good ones are fused.
	if (out.tracking.state != TrackingState::Lost) {
		candidate.pending = false;
		previous_pose = last_pose;
		previous_time_s = last_time_s;
		has_previous = integrated_frames > 0 && !out.tracking.relocalised; // no velocity across a loss
		last_pose = out.tracking.world_from_camera;
		last_time_s = p_frame.timestamp_s;
	}
	const bool poor = out.tracking.state == TrackingState::Poor;
	const bool trusted = out.tracking.state == TrackingState::Good || (poor && (opts.integrate_poor || (opts.integrate_unconstrained && out.tracking.unconstrained)));
	if (trusted) {
		start = Clock::now();
		out.integration = integrate(depth, rgb, last_pose);
		out.integrated = true;
		integrated_frames++;
		out.timings.integrate_ms = ms_since(start);
		start = Clock::now();
		if (opts.reference_search_margin_m > 0.0f) {
			const cv::Mat search = search_intervals(depth, std::clamp(opts.raycast_level, 0, 4), opts.reference_search_margin_m);
			cast_reference(last_pose, &search, &reference);
		} else {
			cast_reference(last_pose, nullptr, &reference);
		}
		out.timings.raycast_ms = ms_since(start);
		if (out.tracking.state == TrackingState::Good && keyframes.consider(depth, rgb, last_pose)) {
			keyframe_total++;
		}
	}
	last_state = out.tracking.state;
	last_colour_held = out.tracking.colour_held;
	frames++;
	out.timings.frame_ms = ms_since(frame_start);
	return out;
}

} // namespace roomprobe
