#include "icp_tracker.h"

#include "depth_pyramid.h"
#include "icp_kernels.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace roomprobe {

namespace {

constexpr int ROWS_PER_STRIPE = 8;

// The Gauss-Newton normal equations J^T J xi = -J^T r, summed in double (millions of float rows).
struct NormalSystem {
	double h[6][6] = {}; // upper triangle of J^T J
	double g[6] = {}; // J^T r
	double sum_squared = 0.0; // of the point-to-plane residuals, metres^2
	int inliers = 0;

	void add(const IcpRow &p_row) {
		for (int i = 0; i < 6; ++i) {
			const double ji = p_row.jacobian[i];
			for (int j = i; j < 6; ++j) {
				h[i][j] += ji * p_row.jacobian[j];
			}
			g[i] += ji * p_row.residual;
		}
	}
	void operator+=(const NormalSystem &p_other) {
		for (int i = 0; i < 6; ++i) {
			for (int j = i; j < 6; ++j) {
				h[i][j] += p_other.h[i][j];
			}
			g[i] += p_other.g[i];
		}
		sum_squared += p_other.sum_squared;
		inliers += p_other.inliers;
	}
};

// The reference's intensity and its gradient (intensity per pixel), NaN where the model has no
// point, for the photometric term.
struct ModelIntensity {
	cv::Mat intensity, gradient_x, gradient_y; // CV_32FC1
};

ModelIntensity model_intensity(const ModelMaps &p_model) {
	ModelIntensity m;
	m.intensity = intensity_of(p_model.colors);
	const int w = m.intensity.cols, h = m.intensity.rows;
	for (int y = 0; y < h; ++y) {
		const cv::Vec3f *points = p_model.points.ptr<cv::Vec3f>(y);
		float *row = m.intensity.ptr<float>(y);
		for (int x = 0; x < w; ++x) {
			if (std::isnan(points[x][0])) {
				row[x] = ICP_NAN;
			}
		}
	}
	m.gradient_x = cv::Mat(h, w, CV_32FC1, cv::Scalar(ICP_NAN));
	m.gradient_y = cv::Mat(h, w, CV_32FC1, cv::Scalar(ICP_NAN));
	for (int y = 1; y + 1 < h; ++y) {
		const float *up = m.intensity.ptr<float>(y - 1), *row = m.intensity.ptr<float>(y), *down = m.intensity.ptr<float>(y + 1);
		float *gx = m.gradient_x.ptr<float>(y), *gy = m.gradient_y.ptr<float>(y);
		for (int x = 1; x + 1 < w; ++x) {
			// NaN propagates: no gradient next to a hole.
			gx[x] = 0.5f * (row[x + 1] - row[x - 1]);
			gy[x] = 0.5f * (down[x] - up[x]);
		}
	}
	return m;
}

IcpModelView model_view(const ModelMaps &p_model, const ModelIntensity *p_intensity) {
	IcpModelView view;
	view.points = p_model.points.ptr<float>();
	view.normals = p_model.normals.ptr<float>();
	CV_Assert(p_model.points.step1() == p_model.normals.step1());
	view.stride = p_model.points.step1();
	view.camera = p_model.camera;
	const Pose camera_from_world = inverse(p_model.world_from_camera);
	view.camera_from_world_rotation = glm::mat3(glm::mat3_cast(camera_from_world.rotation));
	view.camera_from_world_translation = glm::vec3(camera_from_world.translation);
	if (p_intensity != nullptr) {
		view.intensity = p_intensity->intensity.ptr<float>();
		view.gradient_x = p_intensity->gradient_x.ptr<float>();
		view.gradient_y = p_intensity->gradient_y.ptr<float>();
		view.intensity_stride = p_intensity->intensity.step1();
	}
	return view;
}

// The normal equations of one pyramid level at the estimate in p_params: per-stripe partial sums
// in parallel, then their sum in stripe order (the same result whatever the thread count).
NormalSystem accumulate(const FramePyramid &p_frame, int p_level, const IcpKernelParams &p_params, const IcpModelView &p_model) {
	const cv::Mat &vertices = p_frame.vertices[size_t(p_level)];
	const cv::Mat &normals = p_frame.normals[size_t(p_level)];
	const cv::Mat *intensity = p_frame.intensity.empty() ? nullptr : &p_frame.intensity[size_t(p_level)];
	const int rows = vertices.rows, cols = vertices.cols;
	const int stripes = (rows + ROWS_PER_STRIPE - 1) / ROWS_PER_STRIPE;
	std::vector<NormalSystem> partial(static_cast<size_t>(stripes));
	cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range &p_range) {
		for (int s = p_range.start; s < p_range.end; ++s) {
			NormalSystem &system = partial[size_t(s)];
			const int end = std::min(rows, (s + 1) * ROWS_PER_STRIPE);
			for (int y = s * ROWS_PER_STRIPE; y < end; ++y) {
				const cv::Vec3f *v = vertices.ptr<cv::Vec3f>(y);
				const cv::Vec3f *n = normals.ptr<cv::Vec3f>(y);
				const float *i = intensity != nullptr ? intensity->ptr<float>(y) : nullptr;
				for (int x = 0; x < cols; ++x) {
					IcpRow rows_out[2];
					float squared = 0.0f;
					const int count = icp_correspondence(glm::vec3(v[x][0], v[x][1], v[x][2]), glm::vec3(n[x][0], n[x][1], n[x][2]),
							i != nullptr ? i[x] : ICP_NAN, p_params, p_model, rows_out, &squared);
					for (int k = 0; k < count; ++k) {
						system.add(rows_out[k]);
					}
					if (count > 0) {
						system.sum_squared += squared;
						++system.inliers;
					}
				}
			}
		}
	});
	NormalSystem total;
	for (const NormalSystem &p : partial) {
		total += p;
	}
	return total;
}

// Solves the system; false when it is degenerate (the smallest eigenvalue of J^T J below
// p_min_ratio times the largest: some motion is not constrained). r_ratio gets that ratio.
bool solve(const NormalSystem &p_system, double p_min_ratio, cv::Vec6d *r_xi, double *r_ratio) {
	cv::Matx66d h;
	cv::Vec6d g;
	for (int i = 0; i < 6; ++i) {
		for (int j = i; j < 6; ++j) {
			h(i, j) = h(j, i) = p_system.h[i][j];
		}
		g[i] = p_system.g[i];
	}
	cv::Mat eigenvalues;
	cv::eigen(cv::Mat(h), eigenvalues);
	const double largest = eigenvalues.at<double>(0), smallest = eigenvalues.at<double>(5);
	*r_ratio = largest > 0.0 ? smallest / largest : 0.0;
	if (!(*r_ratio >= p_min_ratio)) {
		return false;
	}
	return cv::solve(h, -g, *r_xi, cv::DECOMP_CHOLESKY);
}

// x' = exp(omega) (x - c) + c + delta_t, c the camera centre: world_from_camera gets its rotation
// turned by exp(omega) and its translation moved by delta_t.
Pose apply_update(const Pose &p_pose, const cv::Vec6d &p_xi) {
	const glm::dvec3 omega(p_xi[0], p_xi[1], p_xi[2]);
	const double angle = glm::length(omega);
	const glm::dquat turn = angle > 0.0 ? glm::angleAxis(angle, omega / angle) : glm::dquat(1.0, 0.0, 0.0, 0.0);
	Pose pose;
	pose.rotation = glm::normalize(turn * p_pose.rotation);
	pose.translation = p_pose.translation + glm::dvec3(p_xi[3], p_xi[4], p_xi[5]);
	return pose;
}

IcpKernelParams kernel_params(const IcpOptions &p_options, const Pose &p_pose, int p_level, bool p_colour) {
	IcpKernelParams params;
	params.rotation = glm::mat3(glm::mat3_cast(p_pose.rotation));
	params.translation = glm::vec3(p_pose.translation);
	params.max_distance_m = float(p_options.max_distance_m * std::pow(std::max(1.0, p_options.coarse_distance_growth), p_level));
	params.min_normal_cos = float(std::cos(p_options.max_normal_angle_deg * std::numbers::pi / 180.0));
	params.colour_weight = p_colour ? float(p_options.colour_weight) : 0.0f;
	params.max_colour_difference = float(p_options.max_colour_difference);
	return params;
}

std::string check_inputs(const cv::Mat &p_depth, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const ModelMaps &p_model, bool p_colour) {
	if (p_depth.type() != CV_32FC1 || p_depth.cols != p_camera.width || p_depth.rows != p_camera.height) {
		return "depth must be CV_32FC1 of the camera's size " + std::to_string(p_camera.width) + "x" + std::to_string(p_camera.height);
	}
	const cv::Size model_size(p_model.camera.width, p_model.camera.height);
	if (p_model.points.type() != CV_32FC3 || p_model.normals.type() != CV_32FC3 || p_model.points.size() != model_size ||
			p_model.normals.size() != model_size) {
		return "the model's points and normals must be CV_32FC3 of its camera's size";
	}
	if (p_colour && (p_rgb.type() != CV_8UC3 || p_rgb.size() != p_depth.size() || p_model.colors.type() != CV_8UC3 ||
							p_model.colors.size() != model_size)) {
		return "the colour term needs CV_8UC3 colour of the frame's and the model's sizes";
	}
	return std::string();
}

TrackingResult lost(const Pose &p_initial, const std::string &p_reason, int p_iterations) {
	TrackingResult result;
	result.state = TrackingState::Lost;
	result.reason = p_reason;
	result.world_from_camera = p_initial;
	result.iterations = p_iterations;
	return result;
}

std::string format(double p_value, int p_decimals) {
	char buffer[64];
	std::snprintf(buffer, sizeof(buffer), "%.*f", p_decimals, p_value);
	return buffer;
}

} // namespace

double rotation_difference_deg(const Pose &p_a, const Pose &p_b) {
	const glm::dquat d = glm::inverse(p_a.rotation) * p_b.rotation;
	const double w = std::min(1.0, std::abs(d.w) / glm::length(d));
	return 2.0 * std::acos(w) * 180.0 / std::numbers::pi;
}

double translation_difference_m(const Pose &p_a, const Pose &p_b) {
	return glm::length(p_a.translation - p_b.translation);
}

TrackingResult IcpTracker::track(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const ModelMaps &p_model,
		const Pose &p_initial_world_from_camera) const {
	const bool colour = options.colour_weight != 0.0;
	const std::string input_error = check_inputs(p_depth_m, p_rgb, p_camera, p_model, colour);
	if (!input_error.empty()) {
		return lost(p_initial_world_from_camera, input_error, 0);
	}
	int valid = 0;
	const cv::Mat depth = clean_depth(p_depth_m, float(options.min_depth_m), float(options.max_depth_m), &valid);
	const int total = depth.cols * depth.rows;
	if (valid < options.min_valid_fraction * total || valid == 0) {
		return lost(p_initial_world_from_camera,
				"too few valid depth pixels: " + std::to_string(valid) + " of " + std::to_string(total), 0);
	}
	const int levels = std::clamp(options.levels, 1, IcpOptions::MAX_LEVELS);
	const FramePyramid frame = build_frame_pyramid(depth, colour ? p_rgb : cv::Mat(), p_camera, levels, float(options.pyramid_band_m), options.surface);
	ModelIntensity intensity;
	if (colour) {
		intensity = model_intensity(p_model);
	}
	const IcpModelView model = model_view(p_model, colour ? &intensity : nullptr);

	Pose pose = p_initial_world_from_camera;
	int iterations = 0;
	for (int level = levels - 1; level >= 0; --level) {
		for (int i = 0; i < options.iterations[size_t(level)]; ++i) {
			const NormalSystem system = accumulate(frame, level, kernel_params(options, pose, level, colour), model);
			if (system.inliers < options.min_correspondences) {
				return lost(p_initial_world_from_camera,
						"too few correspondences at level " + std::to_string(level) + ": " + std::to_string(system.inliers), iterations);
			}
			cv::Vec6d xi;
			double ratio = 0.0;
			if (!solve(system, options.min_eigenvalue_ratio, &xi, &ratio)) {
				return lost(p_initial_world_from_camera, "degenerate geometry at level " + std::to_string(level) +
								": eigenvalue ratio " + format(ratio, 9) + " below " + format(options.min_eigenvalue_ratio, 9),
						iterations);
			}
			pose = apply_update(pose, xi);
			++iterations;
			const double step_m = std::sqrt(xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]);
			const double step_rad = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
			if (step_m < options.min_update_m && step_rad < options.min_update_rad) {
				break;
			}
		}
	}

	// The support of the final pose, at the finest level, geometry only.
	const NormalSystem final_system = accumulate(frame, 0, kernel_params(options, pose, 0, false), model);
	TrackingResult result;
	result.world_from_camera = pose;
	result.iterations = iterations;
	result.inlier_fraction = double(final_system.inliers) / double(valid);
	result.rmse_m = final_system.inliers > 0 ? std::sqrt(final_system.sum_squared / final_system.inliers) : 0.0;

	const double jump_m = translation_difference_m(pose, p_initial_world_from_camera);
	const double jump_deg = rotation_difference_deg(pose, p_initial_world_from_camera);
	std::string reason;
	if (!is_finite(pose)) {
		reason = "the estimate is not finite";
	} else if (jump_m > options.max_jump_m || jump_deg > options.max_jump_deg) {
		reason = "the pose jumped " + format(jump_m, 3) + " m and " + format(jump_deg, 1) + " deg from the initial guess (limits " +
				format(options.max_jump_m, 3) + " m, " + format(options.max_jump_deg, 1) + " deg)";
	} else if (result.inlier_fraction < options.lost_inlier_fraction) {
		reason = "too few inliers: " + std::to_string(final_system.inliers) + " of " + std::to_string(valid) + " valid depth pixels";
	}
	if (!reason.empty()) {
		TrackingResult held = lost(p_initial_world_from_camera, reason, iterations);
		held.inlier_fraction = result.inlier_fraction;
		held.rmse_m = result.rmse_m;
		return held;
	}
	if (result.inlier_fraction < options.good_inlier_fraction) {
		result.state = TrackingState::Poor;
		result.reason = "weak support: inlier fraction " + format(result.inlier_fraction, 3) + " below " + format(options.good_inlier_fraction, 3);
	} else if (result.rmse_m > options.max_good_rmse_m) {
		result.state = TrackingState::Poor;
		result.reason = "large residual: RMSE " + format(result.rmse_m * 1000.0, 1) + " mm above " + format(options.max_good_rmse_m * 1000.0, 1) + " mm";
	} else {
		result.state = TrackingState::Good;
	}
	return result;
}

ModelMaps make_model_maps(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera,
		const SurfaceOptions &p_surface) {
	ModelMaps maps;
	maps.camera = p_camera;
	maps.world_from_camera = p_world_from_camera;
	maps.depth = clean_depth(p_depth_m, 0.0f, std::numeric_limits<float>::max());
	const cv::Mat smooth = smooth_depth(maps.depth, p_surface.smoothing_radius_px, p_surface.smoothing_band_m);
	const cv::Mat vertices = compute_vertex_map(smooth, p_camera);
	const cv::Mat normals = compute_normal_map(vertices, p_surface.max_jump_relative);
	const glm::mat3 rotation(glm::mat3_cast(p_world_from_camera.rotation));
	const glm::vec3 translation(p_world_from_camera.translation);
	maps.points.create(vertices.size(), CV_32FC3);
	maps.normals.create(vertices.size(), CV_32FC3);
	cv::parallel_for_(cv::Range(0, vertices.rows), [&](const cv::Range &p_range) {
		for (int y = p_range.start; y < p_range.end; ++y) {
			const cv::Vec3f *v = vertices.ptr<cv::Vec3f>(y);
			const cv::Vec3f *n = normals.ptr<cv::Vec3f>(y);
			cv::Vec3f *points = maps.points.ptr<cv::Vec3f>(y);
			cv::Vec3f *world_normals = maps.normals.ptr<cv::Vec3f>(y);
			for (int x = 0; x < vertices.cols; ++x) {
				// NaN stays NaN through the transform.
				const glm::vec3 p = rotation * glm::vec3(v[x][0], v[x][1], v[x][2]) + translation;
				const glm::vec3 wn = rotation * glm::vec3(n[x][0], n[x][1], n[x][2]);
				points[x] = cv::Vec3f(p.x, p.y, p.z);
				world_normals[x] = cv::Vec3f(wn.x, wn.y, wn.z);
			}
		}
	});
	maps.colors = cv::Mat(vertices.size(), CV_8UC3, cv::Scalar::all(0));
	if (!p_rgb.empty()) {
		CV_Assert(p_rgb.type() == CV_8UC3 && p_rgb.size() == vertices.size());
		p_rgb.copyTo(maps.colors, maps.depth == maps.depth); // NaN != NaN: colour where there is depth
	}
	return maps;
}

} // namespace roomprobe
