#include "icp_tracker.h"

#include <parallel/parallel_for.h>

#include "depth_pyramid.h"
#include "icp_accumulate_simd.h"
#include "icp_kernels.h"
#include "icp_reduce_gpu.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <iterator>
#include <cstdio>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace roomprobe {

namespace {

constexpr int ROWS_PER_STRIPE = 8;

// The Gauss-Newton normal equations J^T J xi = -J^T r, summed in double (millions of float rows).
struct NormalSystem {
	double h[6][6] = {}; // upper triangle of J^T J (rows come in through RowSums)
	double g[6] = {}; // J^T r
	double sum_squared = 0.0; // of the point-to-plane residuals, metres^2
	// Traces of the rotation and translation blocks of the point-to-plane rows alone: the scale
	// of the geometry's information, against which colour's is measured too (condition()).
	double geometry_trace_rotation = 0.0, geometry_trace_translation = 0.0;
	int inliers = 0;

	void operator+=(const NormalSystem &p_other) {
		for (int i = 0; i < 6; ++i) {
			for (int j = i; j < 6; ++j) {
				h[i][j] += p_other.h[i][j];
			}
			g[i] += p_other.g[i];
		}
		sum_squared += p_other.sum_squared;
		geometry_trace_rotation += p_other.geometry_trace_rotation;
		geometry_trace_translation += p_other.geometry_trace_translation;
		inliers += p_other.inliers;
	}
	// Adds one image row's sums, laid out as IcpRowTotals::sums (h's upper triangle row by row,
	// g, the two traces, the squared residuals): RowSums', the AVX2 kernel's and the device's rows.
	template <typename T>
	void add_sums(const T *p_sums) {
		int k = 0;
		for (int a = 0; a < 6; ++a) {
			for (int b = a; b < 6; ++b) {
				h[a][b] += double(p_sums[k++]);
			}
			g[a] += double(p_sums[21 + a]);
		}
		geometry_trace_rotation += double(p_sums[27]);
		geometry_trace_translation += double(p_sums[28]);
		sum_squared += double(p_sums[29]);
	}
};

// One image row's share of a NormalSystem, summed in float (a row has at most a few hundred rows
// of the system: float keeps them to about 1e-5 where the double sum over the frame would not),
// then added to the double system once per image row: the 27 products a row costs are float
// ones the compiler can pack. Laid out as IcpRowTotals::sums.
struct RowSums {
	float sums[IcpRowTotals::SUMS] = {};

	void add(const IcpRow &p_row) {
		const float *j = p_row.jacobian;
		int k = 0;
		for (int a = 0; a < 6; ++a) {
			for (int b = a; b < 6; ++b) {
				sums[k++] += j[a] * j[b];
			}
			sums[21 + a] += j[a] * p_row.residual;
		}
	}
	// The traces and the squared residual of a point-to-plane row (the geometry's scale, and the
	// support of the pose).
	void add_support(const IcpRow &p_row, float p_squared) {
		const float *j = p_row.jacobian;
		sums[27] += j[0] * j[0] + j[1] * j[1] + j[2] * j[2];
		sums[28] += j[3] * j[3] + j[4] * j[4] + j[5] * j[5];
		sums[29] += p_squared;
	}
	// Adds the sums to r_system and starts again from 0.
	void flush(NormalSystem *r_system) {
		r_system->add_sums(sums);
		std::fill(std::begin(sums), std::end(sums), 0.0f);
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

// The normal equations of one pyramid level at the estimate in p_params, from every p_stride-th
// pixel of every p_stride-th row: per-stripe partial sums in parallel, then their sum in stripe
// order (the same result whatever the thread count). p_simd: the AVX2 kernel for geometry rows
// where the CPU has it (IcpOptions::simd).
NormalSystem accumulate(const FramePyramid &p_frame, int p_level, int p_stride, const IcpKernelParams &p_params, const IcpModelView &p_model,
		bool p_simd) {
	const cv::Mat &vertices = p_frame.vertices[size_t(p_level)];
	const cv::Mat &normals = p_frame.normals[size_t(p_level)];
	const cv::Mat *intensity = p_frame.intensity.empty() ? nullptr : &p_frame.intensity[size_t(p_level)];
	const int cols = vertices.cols;
	const int rows = (vertices.rows + p_stride - 1) / p_stride; // sampled rows
	const int stripes = (rows + ROWS_PER_STRIPE - 1) / ROWS_PER_STRIPE;
	// Geometry alone: eight pixels at a time where the CPU has AVX2, the row's remainder scalar.
	const bool simd = p_simd && icp_simd_available() && (intensity == nullptr || p_model.intensity == nullptr || p_params.colour_weight == 0.0f);
	const int samples = (cols + p_stride - 1) / p_stride;
	const int simd_samples = simd ? samples / 8 * 8 : 0;
	std::vector<NormalSystem> partial(static_cast<size_t>(stripes));
	parallel_for(cv::Range(0, stripes), [&](const cv::Range &p_range) {
		for (int s = p_range.start; s < p_range.end; ++s) {
			NormalSystem &system = partial[size_t(s)];
			const int end = std::min(rows, (s + 1) * ROWS_PER_STRIPE);
			for (int row = s * ROWS_PER_STRIPE; row < end; ++row) {
				const int y = row * p_stride;
				const cv::Vec3f *v = vertices.ptr<cv::Vec3f>(y);
				const cv::Vec3f *n = normals.ptr<cv::Vec3f>(y);
				const float *i = intensity != nullptr ? intensity->ptr<float>(y) : nullptr;
				if (simd_samples > 0) {
					IcpRowTotals totals;
					icp_accumulate_row_simd(&v[0][0], &n[0][0], simd_samples, p_stride, p_params, p_model, &totals);
					system.add_sums(totals.sums);
					system.inliers += totals.inliers;
				}
				RowSums sums;
				for (int x = simd_samples * p_stride; x < cols; x += p_stride) {
					IcpRow rows_out[2];
					float squared = 0.0f;
					const int count = icp_correspondence(glm::vec3(v[x][0], v[x][1], v[x][2]), glm::vec3(n[x][0], n[x][1], n[x][2]),
							i != nullptr ? i[x] : ICP_NAN, p_params, p_model, rows_out, &squared);
					for (int k = 0; k < count; ++k) {
						sums.add(rows_out[k]);
					}
					if (count > 0) {
						sums.add_support(rows_out[0], squared);
						++system.inliers;
					}
				}
				sums.flush(&system);
			}
		}
	});
	NormalSystem total;
	for (const NormalSystem &p : partial) {
		total += p;
	}
	return total;
}

// The normal equations from the device's row sums (IcpReducerGpu::ROW_FLOATS each), added in
// double in row order as accumulate adds its rows: a row's first 30 floats are a RowSums, in its
// order (icp_reduce.comp's Rows), then the inlier count.
static_assert(IcpReducerGpu::ROW_FLOATS > IcpRowTotals::SUMS);
NormalSystem system_from_rows(const float *p_rows, int p_row_count) {
	NormalSystem system;
	for (int r = 0; r < p_row_count; r++) {
		const float *row = p_rows + size_t(r) * IcpReducerGpu::ROW_FLOATS;
		system.add_sums(row);
		system.inliers += int(row[IcpRowTotals::SUMS]);
	}
	return system;
}

// Valid (non-NaN) depths among every p_stride-th pixel of every p_stride-th row.
int count_sampled_valid(const cv::Mat &p_depth_m, int p_stride) {
	int valid = 0;
	for (int y = 0; y < p_depth_m.rows; y += p_stride) {
		const float *row = p_depth_m.ptr<float>(y);
		for (int x = 0; x < p_depth_m.cols; x += p_stride) {
			valid += row[x] > 0.0f ? 1 : 0; // false for NaN
		}
	}
	return valid;
}

// The normal equations made unit-free: S H S with S scaling the rotation and the translation
// blocks of the geometry's rows to unit trace. An eigenvalue is then the information along its
// direction as a share of the geometry's: a plane seen alone gives about 1 along its normal and
// 0.5 for each of its two tilts, and only a noise floor (about 0.002) to sliding along it or
// turning about its normal. Photometric rows add on the same scale (not renormalised: their
// information is texture, not noise, and must not dilute the geometry's).
struct Conditioning {
	cv::Vec6d eigenvalues; // descending
	cv::Matx66d eigenvectors; // rows, in the scaled space
	cv::Vec6d scale; // the diagonal of S
	cv::Vec6d g; // J^T r, unscaled
	bool ok = false; // finite, and some information at all
};

Conditioning condition(const NormalSystem &p_system) {
	Conditioning c;
	for (int i = 0; i < 6; ++i) {
		c.g[i] = p_system.g[i];
	}
	const double rotation_trace = p_system.geometry_trace_rotation, translation_trace = p_system.geometry_trace_translation;
	if (!(rotation_trace > 0.0) || !(translation_trace > 0.0) || !std::isfinite(rotation_trace + translation_trace)) {
		return c;
	}
	for (int i = 0; i < 3; ++i) {
		c.scale[i] = 1.0 / std::sqrt(rotation_trace);
		c.scale[i + 3] = 1.0 / std::sqrt(translation_trace);
	}
	cv::Matx66d scaled;
	for (int i = 0; i < 6; ++i) {
		for (int j = 0; j < 6; ++j) {
			// h holds the upper triangle only.
			scaled(i, j) = p_system.h[std::min(i, j)][std::max(i, j)] * c.scale[i] * c.scale[j];
		}
	}
	cv::Mat values, vectors;
	if (!cv::eigen(cv::Mat(scaled), values, vectors)) {
		return c;
	}
	for (int i = 0; i < 6; ++i) {
		c.eigenvalues[i] = values.at<double>(i);
		for (int j = 0; j < 6; ++j) {
			c.eigenvectors(i, j) = vectors.at<double>(i, j);
		}
	}
	c.ok = std::isfinite(c.eigenvalues[0]) && c.eigenvalues[0] > 0.0;
	return c;
}

// The Gauss-Newton step in the directions whose share of the information is at least
// p_min_constraint; the others are not moved (their estimate stays where the guess put it). False
// when no direction is constrained or the step is not finite.
bool solve(const Conditioning &p_conditioning, double p_min_constraint, cv::Vec6d *r_xi) {
	if (!p_conditioning.ok) {
		return false;
	}
	cv::Vec6d scaled_g, step_scaled;
	for (int i = 0; i < 6; ++i) {
		scaled_g[i] = p_conditioning.g[i] * p_conditioning.scale[i];
	}
	int used = 0;
	for (int k = 0; k < 6; ++k) {
		const double lambda = p_conditioning.eigenvalues[k];
		if (!(lambda >= p_min_constraint)) {
			continue;
		}
		double along = 0.0;
		for (int i = 0; i < 6; ++i) {
			along += p_conditioning.eigenvectors(k, i) * scaled_g[i];
		}
		for (int i = 0; i < 6; ++i) {
			step_scaled[i] -= along / lambda * p_conditioning.eigenvectors(k, i);
		}
		++used;
	}
	for (int i = 0; i < 6; ++i) {
		(*r_xi)[i] = step_scaled[i] * p_conditioning.scale[i];
		if (!std::isfinite((*r_xi)[i])) {
			return false;
		}
	}
	return used > 0;
}

std::string format(double p_value, int p_decimals) {
	char buffer[64];
	std::snprintf(buffer, sizeof(buffer), "%.*f", p_decimals, p_value);
	return buffer;
}

// "translation along (0.98, 0.00, -0.17)" or "rotation about (...)", world axes: the weakest
// direction of p_conditioning, by which of its parts (both unit-free) is larger.
std::string weakest_direction(const Conditioning &p_conditioning) {
	const int k = 5;
	glm::dvec3 rotation, translation;
	for (int i = 0; i < 3; ++i) {
		rotation[i] = p_conditioning.eigenvectors(k, i);
		translation[i] = p_conditioning.eigenvectors(k, i + 3);
	}
	const bool translating = glm::length(translation) >= glm::length(rotation);
	const glm::dvec3 axis = glm::normalize(translating ? translation : rotation);
	return std::string(translating ? "translation along (" : "rotation about (") + format(axis.x, 2) + ", " + format(axis.y, 2) + ", " +
			format(axis.z, 2) + ")";
}

// The part of the update p_xi (apply_update's form) that lies along the directions p_geometry
// leaves free (information share below p_min_constraint), projected in its unit-free space.
cv::Vec6d free_part(const Conditioning &p_geometry, double p_min_constraint, const cv::Vec6d &p_xi) {
	cv::Vec6d unit_free;
	for (int i = 0; i < 6; ++i) {
		unit_free[i] = p_xi[i] / p_geometry.scale[i];
	}
	cv::Vec6d out;
	for (int k = 0; k < 6; ++k) {
		if (p_geometry.eigenvalues[k] >= p_min_constraint) {
			continue;
		}
		double along = 0.0;
		for (int i = 0; i < 6; ++i) {
			along += p_geometry.eigenvectors(k, i) * unit_free[i];
		}
		for (int i = 0; i < 6; ++i) {
			out[i] += along * p_geometry.eigenvectors(k, i) * p_geometry.scale[i];
		}
	}
	return out;
}

// The move from p_from to p_to as an update (apply_update's form).
cv::Vec6d update_between(const Pose &p_from, const Pose &p_to) {
	glm::dquat turn = glm::normalize(p_to.rotation * glm::inverse(p_from.rotation));
	if (turn.w < 0.0) {
		turn = -turn; // the short way round
	}
	const double angle = glm::angle(turn);
	const glm::dvec3 omega = angle > 1e-12 ? glm::axis(turn) * angle : glm::dvec3(0.0);
	const glm::dvec3 delta = p_to.translation - p_from.translation;
	return cv::Vec6d(omega.x, omega.y, omega.z, delta.x, delta.y, delta.z);
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

// The colour slide guard (IcpOptions::max_colour_slide_m; off at 0): the move from p_guess to *io_pose
// along the directions the finest level's geometry (p_geometry) leaves free, which only colour
// can have made, is undone when it is larger than a hand's departure from the guess. Returns why
// ("" when the pose stands).
std::string hold_colour_slide(const IcpOptions &p_options, const Conditioning &p_geometry, const Pose &p_guess, Pose *io_pose) {
	if (!(p_options.max_colour_slide_m > 0.0) || !p_geometry.ok) {
		return std::string();
	}
	const cv::Vec6d slide = free_part(p_geometry, p_options.min_constraint, update_between(p_guess, *io_pose));
	const double slide_m = std::sqrt(slide[3] * slide[3] + slide[4] * slide[4] + slide[5] * slide[5]);
	const double slide_deg = std::sqrt(slide[0] * slide[0] + slide[1] * slide[1] + slide[2] * slide[2]) * 180.0 / std::numbers::pi;
	if (slide_m <= p_options.max_colour_slide_m && slide_deg <= p_options.max_colour_slide_deg) {
		return std::string();
	}
	*io_pose = apply_update(*io_pose, -slide);
	return "the colour term moved the pose " + format(slide_m * 1000.0, 1) + " mm and " + format(slide_deg, 2) + " deg from the guess along " +
			weakest_direction(p_geometry) + ", which the geometry leaves free (limits " + format(p_options.max_colour_slide_m * 1000.0, 1) + " mm, " +
			format(p_options.max_colour_slide_deg, 2) + " deg): kept at the guess there";
}

IcpKernelParams kernel_params(const IcpOptions &p_options, const Pose &p_pose, int p_level, bool p_colour) {
	IcpKernelParams params;
	params.rotation = glm::mat3(glm::mat3_cast(p_pose.rotation));
	params.translation = glm::vec3(p_pose.translation);
	params.max_distance_m = float(p_options.max_distance_m * std::pow(std::max(1.0, p_options.coarse_distance_growth), p_level));
	params.min_normal_cos = float(std::cos(p_options.max_normal_angle_deg * std::numbers::pi / 180.0));
	params.colour_weight = p_colour ? float(p_options.colour_weight) : 0.0f;
	params.max_colour_difference = float(p_options.max_colour_difference);
	// Noise weights at the finest level only: the coarse levels are there to bring a large step
	// in, and that needs the far surfaces' leverage as much as the near ones'.
	const DepthNoiseModel &noise = p_options.depth_noise;
	params.noise_a_m = float(noise.a_m);
	params.noise_b_per_m2 = p_level == 0 ? float(noise.b_per_m2) : 0.0f;
	params.noise_c_m = float(noise.c_m);
	params.noise_reference_sigma_m = float(noise.sigma_m(std::max(noise.reference_m, noise.c_m)));
	return params;
}

// The normal equations of one frame against one reference, at any level and pose: on the device
// when the tracker has one (the same pairs, rows and sums: icp_reduce_gpu.h), else on the CPU. A
// device failure puts this frame and later ones back on the CPU. The CPU pyramid and the
// reference's intensity are made when first needed.
class FrameSystems {
public:
	FrameSystems(const IcpOptions &p_options, const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const ModelMaps &p_model,
			int p_levels, int p_finest_stride, IcpReducerGpu *p_reducer) :
			options(p_options), depth(p_depth_m), rgb(p_rgb), camera(p_camera), model(p_model), levels(p_levels), finest_stride(p_finest_stride),
			reducer(p_reducer), geometry_model(model_view(p_model, nullptr)), colour_model(geometry_model) {
		if (reducer == nullptr) {
			return;
		}
		reducer_lock = std::unique_lock<std::mutex>(reducer->mutex());
		if (!reducer->build_frame(depth, rgb, camera, levels, float(options.pyramid_band_m), options.surface, finest_stride, &gpu_error) ||
				!reducer->set_model(geometry_model, &gpu_error)) {
			give_up_gpu();
		}
	}

	NormalSystem at(int p_level, const Pose &p_pose, bool p_colour) {
		if (p_colour && intensity.intensity.empty()) {
			intensity = model_intensity(model);
			colour_model = model_view(model, &intensity);
			if (reducer != nullptr && !reducer->set_model(colour_model, &gpu_error)) {
				give_up_gpu();
			}
		}
		const IcpKernelParams params = kernel_params(options, p_pose, p_level, p_colour);
		if (reducer != nullptr) {
			const float *rows = nullptr;
			int row_count = 0;
			if (reducer->reduce(p_level, params, &rows, &row_count, &gpu_error)) {
				return system_from_rows(rows, row_count);
			}
			give_up_gpu();
		}
		return accumulate(cpu_frame(), p_level, p_level == 0 ? finest_stride : 1, params, p_colour ? colour_model : geometry_model, options.simd);
	}

private:
	const FramePyramid &cpu_frame() {
		if (!pyramid) {
			pyramid = build_frame_pyramid(depth, rgb, camera, levels, float(options.pyramid_band_m), options.surface, finest_stride);
		}
		return *pyramid;
	}
	void give_up_gpu() {
		reducer->set_failed("ICP on the GPU: " + gpu_error);
		reducer = nullptr;
	}

	const IcpOptions &options;
	const cv::Mat &depth;
	const cv::Mat rgb; // empty: no colour term
	const PinholeIntrinsics camera;
	const ModelMaps &model;
	const int levels, finest_stride;
	IcpReducerGpu *reducer; // null: the CPU
	std::unique_lock<std::mutex> reducer_lock; // its buffers are this frame's while held
	std::string gpu_error;
	std::optional<FramePyramid> pyramid;
	ModelIntensity intensity; // made when the colour term is first needed
	const IcpModelView geometry_model;
	IcpModelView colour_model;
};

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

} // namespace

bool IcpTracker::uses_gpu() const {
	return gpu && !gpu->has_failed();
}

std::string IcpTracker::compute_problem() const {
	return gpu ? gpu->failure() : std::string();
}

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
	// Colour takes part only where both sides have it: a depth-only caller tracks on geometry.
	const bool colour = options.colour_weight != 0.0 && !p_rgb.empty() && !p_model.colors.empty();
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
	const double hold = std::max(options.min_constraint, options.hold_constraint);
	const int levels = std::clamp(options.levels, 1, IcpOptions::MAX_LEVELS);
	// The finest level pairs a sample of its pixels (IcpOptions::finest_stride_px); the inlier
	// fraction is of the valid pixels sampled.
	const int finest_stride = std::max(1, options.finest_stride_px);
	const int sampled_valid = finest_stride == 1 ? valid : count_sampled_valid(depth, finest_stride);
	FrameSystems systems(options, depth, colour ? p_rgb : cv::Mat(), p_camera, p_model, levels, finest_stride, uses_gpu() ? gpu.get() : nullptr);
	auto system_at = [&](int p_level, const Pose &p_pose, bool p_colour) { return systems.at(p_level, p_pose, p_colour); };

	Pose pose = p_initial_world_from_camera;
	int iterations = 0;
	bool colour_used = false, colour_any = false;
	Conditioning finest;
	Conditioning geometry_finest; // the finest level's geometry alone, at its first iteration
	// The finest level's last system, when its step was below the thresholds: the pose it was taken
	// at is the final one to within them, so it stands for the final pose's support.
	NormalSystem converged_finest;
	bool converged = false;
	for (int level = levels - 1; level >= 0; --level) {
		bool colour_level = colour && options.colour_always;
		for (int i = 0; i < options.iterations[size_t(level)]; ++i) {
			NormalSystem system = system_at(level, pose, colour_level);
			Conditioning conditioning = condition(system);
			if (level == 0 && i == 0 && options.max_colour_slide_m > 0.0) {
				// For the colour slide guard alone: with colour at every level, one more system.
				geometry_finest = colour_level ? condition(system_at(0, pose, false)) : conditioning;
			}
			if (i == 0 && colour && !colour_level && conditioning.ok && conditioning.eigenvalues[5] < hold) {
				// The geometry leaves a direction free at this level: the photometric rows constrain it.
				colour_level = true;
				system = system_at(level, pose, true);
				conditioning = condition(system);
			}
			if (system.inliers < options.min_correspondences) {
				return lost(p_initial_world_from_camera,
						"too few correspondences at level " + std::to_string(level) + ": " + std::to_string(system.inliers), iterations);
			}
			cv::Vec6d xi;
			if (!solve(conditioning, hold, &xi)) {
				return lost(p_initial_world_from_camera, "degenerate: no direction constrained at level " + std::to_string(level), iterations);
			}
			if (level == 0) {
				finest = conditioning;
				colour_used = colour_level;
			}
			colour_any = colour_any || colour_level;
			pose = apply_update(pose, xi);
			++iterations;
			const double step_m = std::sqrt(xi[3] * xi[3] + xi[4] * xi[4] + xi[5] * xi[5]);
			const double step_rad = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
			if (step_m < options.min_update_m && step_rad < options.min_update_rad) {
				if (level == 0) {
					converged_finest = system;
					converged = true;
				}
				break;
			}
		}
	}

	const std::string held_reason = colour_any ? hold_colour_slide(options, geometry_finest, p_initial_world_from_camera, &pose) : std::string();
	if (!held_reason.empty()) {
		converged = false; // the pose moved
	}

	// The support of the final pose, at the finest level, geometry only.
	const NormalSystem final_system = converged ? converged_finest : system_at(0, pose, false);
	if (!finest.ok) {
		finest = condition(final_system);
	}
	TrackingResult result;
	result.world_from_camera = pose;
	result.iterations = iterations;
	result.inlier_fraction = double(final_system.inliers) / double(std::max(1, sampled_valid));
	result.rmse_m = final_system.inliers > 0 ? std::sqrt(final_system.sum_squared / final_system.inliers) : 0.0;
	result.constraint = finest.ok ? finest.eigenvalues[5] : 0.0;
	result.colour_used = colour_used;

	const double jump_m = translation_difference_m(pose, p_initial_world_from_camera);
	const double jump_deg = rotation_difference_deg(pose, p_initial_world_from_camera);
	std::string reason;
	if (!is_finite(pose)) {
		reason = "the estimate is not finite";
	} else if (jump_m > options.max_jump_m || jump_deg > options.max_jump_deg) {
		reason = "the pose jumped " + format(jump_m, 3) + " m and " + format(jump_deg, 1) + " deg from the initial guess (limits " +
				format(options.max_jump_m, 3) + " m, " + format(options.max_jump_deg, 1) + " deg)";
	} else if (result.inlier_fraction < options.lost_inlier_fraction) {
		reason = "too few inliers: " + std::to_string(final_system.inliers) + " of " + std::to_string(sampled_valid) + " valid depth pixels" +
				(finest_stride > 1 ? " sampled" : "");
	}
	if (!reason.empty()) {
		TrackingResult held = lost(p_initial_world_from_camera, reason, iterations);
		held.inlier_fraction = result.inlier_fraction;
		held.rmse_m = result.rmse_m;
		held.constraint = result.constraint;
		held.colour_used = result.colour_used;
		return held;
	}
	if (!held_reason.empty()) {
		result.state = TrackingState::Poor;
		result.colour_held = true;
		result.unconstrained = result.inlier_fraction >= options.good_inlier_fraction && result.rmse_m <= options.max_good_rmse_m;
		result.reason = held_reason;
	} else if (!(result.constraint >= options.min_constraint)) {
		// Nothing fixes this direction: the estimate along it is the guess, not a measurement.
		result.state = TrackingState::Poor;
		result.unconstrained = result.inlier_fraction >= options.good_inlier_fraction && result.rmse_m <= options.max_good_rmse_m;
		result.reason = std::string("flat geometry: ") + (finest.ok ? weakest_direction(finest) : std::string("the pose")) +
				" unconstrained (its share of the information " + format(result.constraint, 4) + " below " + format(options.min_constraint, 4) +
				(colour ? ", even with the colour term)" : "; the colour term is off or has no colour)");
	} else if (result.inlier_fraction < options.good_inlier_fraction) {
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
	parallel_for(cv::Range(0, vertices.rows), [&](const cv::Range &p_range) {
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
