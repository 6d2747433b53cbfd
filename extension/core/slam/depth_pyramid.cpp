#include "depth_pyramid.h"

#include <parallel/parallel_for.h>

#include "icp_kernels.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cmath>
#include <vector>

namespace roomprobe {

namespace {

// Rows per parallel_for_ stripe: enough work per task, and a fixed split.
constexpr int ROWS_PER_STRIPE = 16;

template <typename Body>
void for_rows(int p_rows, const Body &p_body) {
	const int stripes = (p_rows + ROWS_PER_STRIPE - 1) / ROWS_PER_STRIPE;
	parallel_for(cv::Range(0, stripes), [&](const cv::Range &p_range) {
		for (int s = p_range.start; s < p_range.end; ++s) {
			const int end = std::min(p_rows, (s + 1) * ROWS_PER_STRIPE);
			for (int y = s * ROWS_PER_STRIPE; y < end; ++y) {
				p_body(y);
			}
		}
	});
}

// One row of smooth_depth: the same sums as smooth_depth_pixel, in the same order (window row by
// row, left to right), but taken tap by tap along the whole row, so that the inner loop runs over
// pixels and the compiler vectorises it; a tap that fails the band test adds exactly 0. The result
// equals smooth_depth_pixel's to the bit (tests/core/test_slam_tracking.cpp). p_sum and
// p_weight_sum: scratch of p_width floats.
void smooth_depth_row(const float *p_depth, size_t p_stride, int p_width, int p_height, int p_y, int p_radius, float p_band_m,
		const float *p_weights, float *p_sum, float *p_weight_sum, float *r_row) {
	const float *centre = p_depth + size_t(p_y) * p_stride;
	std::fill(p_sum, p_sum + p_width, 0.0f);
	std::fill(p_weight_sum, p_weight_sum + p_width, 0.0f);
	const int side = 2 * p_radius + 1;
	for (int dy = -p_radius; dy <= p_radius; ++dy) {
		const int y = p_y + dy;
		if (y < 0 || y >= p_height) {
			continue;
		}
		const float *row = p_depth + size_t(y) * p_stride;
		for (int dx = -p_radius; dx <= p_radius; ++dx) {
			const float weight = p_weights[size_t((dy + p_radius) * side + dx + p_radius)];
			// Pixels x whose tap x + dx lies inside the image.
			const int begin = std::max(0, -dx), end = std::min(p_width, p_width - dx);
			const float *taps = row + dx;
			for (int x = begin; x < end; ++x) {
				// Computed whatever the test says, and masked with integer operations: GCC (with
				// -ftrapping-math, the default) turns no floating-point select into a vector one.
				const float d = taps[x];
				const uint32_t near = -uint32_t(std::abs(d - centre[x]) <= p_band_m); // all ones or 0; false for NaN
				p_sum[x] += std::bit_cast<float>(std::bit_cast<uint32_t>(weight * d) & near);
				p_weight_sum[x] += std::bit_cast<float>(std::bit_cast<uint32_t>(weight) & near);
			}
		}
	}
	for (int x = 0; x < p_width; ++x) {
		// Holes stay holes (a valid centre always counts itself, so its weight sum is not 0).
		const uint32_t hole = -uint32_t(!(centre[x] > 0.0f));
		const float mean = p_sum[x] / p_weight_sum[x];
		r_row[x] = std::bit_cast<float>((std::bit_cast<uint32_t>(mean) & ~hole) | (std::bit_cast<uint32_t>(ICP_NAN) & hole));
	}
}

} // namespace

cv::Mat clean_depth(const cv::Mat &p_depth_m, float p_min_depth_m, float p_max_depth_m, int *r_valid_count, double p_depth_scale_m) {
	cv::Mat depth;
	if (p_depth_m.type() == CV_16UC1) {
		p_depth_m.convertTo(depth, CV_32FC1, p_depth_scale_m);
	} else {
		CV_Assert(p_depth_m.type() == CV_32FC1);
		depth = p_depth_m.clone();
	}
	std::atomic<int> valid{ 0 };
	for_rows(depth.rows, [&](int y) {
		float *row = depth.ptr<float>(y);
		int count = 0;
		for (int x = 0; x < depth.cols; ++x) {
			// Also false for NaN.
			if (row[x] > 0.0f && row[x] >= p_min_depth_m && row[x] <= p_max_depth_m) {
				++count;
			} else {
				row[x] = ICP_NAN;
			}
		}
		valid += count;
	});
	if (r_valid_count != nullptr) {
		*r_valid_count = valid;
	}
	return depth;
}

cv::Mat downsample_depth(const cv::Mat &p_depth_m, float p_band_m) {
	CV_Assert(p_depth_m.type() == CV_32FC1);
	cv::Mat half(p_depth_m.rows / 2, p_depth_m.cols / 2, CV_32FC1);
	const float *source = p_depth_m.ptr<float>();
	const size_t stride = p_depth_m.step1();
	for_rows(half.rows, [&](int y) {
		float *row = half.ptr<float>(y);
		for (int x = 0; x < half.cols; ++x) {
			row[x] = downsample_depth_pixel(source, stride, p_depth_m.cols, p_depth_m.rows, x, y, p_band_m);
		}
	});
	return half;
}

std::vector<float> smoothing_weights(int p_radius) {
	const int radius = std::max(0, p_radius);
	const int side = 2 * radius + 1;
	const float sigma = 0.5f * float(radius) + 0.5f;
	std::vector<float> weights(static_cast<size_t>(side * side));
	for (int dy = -radius; dy <= radius; ++dy) {
		for (int dx = -radius; dx <= radius; ++dx) {
			weights[size_t((dy + radius) * side + dx + radius)] = std::exp(-float(dx * dx + dy * dy) / (2.0f * sigma * sigma));
		}
	}
	return weights;
}

cv::Mat smooth_depth(const cv::Mat &p_depth_m, int p_radius, float p_band_m) {
	CV_Assert(p_depth_m.type() == CV_32FC1);
	if (p_radius <= 0) {
		return p_depth_m.clone();
	}
	const std::vector<float> weights = smoothing_weights(p_radius);
	cv::Mat smooth(p_depth_m.size(), CV_32FC1);
	const int width = p_depth_m.cols, height = p_depth_m.rows;
	const int stripes = (height + ROWS_PER_STRIPE - 1) / ROWS_PER_STRIPE;
	parallel_for(cv::Range(0, stripes), [&](const cv::Range &p_range) {
		std::vector<float> sum(static_cast<size_t>(width)), weight_sum(static_cast<size_t>(width));
		for (int s = p_range.start; s < p_range.end; ++s) {
			const int end = std::min(height, (s + 1) * ROWS_PER_STRIPE);
			for (int y = s * ROWS_PER_STRIPE; y < end; ++y) {
				smooth_depth_row(p_depth_m.ptr<float>(), p_depth_m.step1(), width, height, y, p_radius, p_band_m, weights.data(), sum.data(),
						weight_sum.data(), smooth.ptr<float>(y));
			}
		}
	});
	return smooth;
}

cv::Mat compute_vertex_map(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera) {
	CV_Assert(p_depth_m.type() == CV_32FC1);
	cv::Mat vertices(p_depth_m.size(), CV_32FC3);
	for_rows(p_depth_m.rows, [&](int y) {
		const float *depth = p_depth_m.ptr<float>(y);
		cv::Vec3f *row = vertices.ptr<cv::Vec3f>(y);
		for (int x = 0; x < p_depth_m.cols; ++x) {
			if (depth[x] > 0.0f) {
				const glm::vec3 v = p_camera.unproject({ float(x), float(y) }, depth[x]);
				row[x] = cv::Vec3f(v.x, v.y, v.z);
			} else {
				row[x] = cv::Vec3f(ICP_NAN, ICP_NAN, ICP_NAN);
			}
		}
	});
	return vertices;
}

cv::Mat compute_normal_map(const cv::Mat &p_vertices, float p_max_jump_relative, int p_sample_stride) {
	CV_Assert(p_vertices.type() == CV_32FC3 && p_sample_stride >= 1);
	cv::Mat normals(p_vertices.size(), CV_32FC3, cv::Scalar::all(ICP_NAN));
	const float *source = p_vertices.ptr<float>();
	const size_t stride = p_vertices.step1();
	for_rows((p_vertices.rows + p_sample_stride - 1) / p_sample_stride, [&](int p_sampled_row) {
		const int y = p_sampled_row * p_sample_stride;
		cv::Vec3f *row = normals.ptr<cv::Vec3f>(y);
		for (int x = 0; x < p_vertices.cols; x += p_sample_stride) {
			const glm::vec3 n = normal_pixel(source, stride, p_vertices.cols, p_vertices.rows, x, y, p_max_jump_relative);
			row[x] = cv::Vec3f(n.x, n.y, n.z);
		}
	});
	return normals;
}

void model_normals_from_points(ModelMaps *io_maps, float p_max_jump_relative) {
	const Pose camera_from_world = inverse(io_maps->world_from_camera);
	const glm::dmat3 to_camera = glm::mat3_cast(camera_from_world.rotation), to_world = glm::transpose(to_camera);
	const glm::dvec3 shift = camera_from_world.translation;
	cv::Mat vertices(io_maps->points.size(), CV_32FC3);
	for_rows(vertices.rows, [&](int y) {
		const cv::Vec3f *world = io_maps->points.ptr<cv::Vec3f>(y);
		cv::Vec3f *camera = vertices.ptr<cv::Vec3f>(y);
		for (int x = 0; x < vertices.cols; ++x) {
			const glm::vec3 v(to_camera * glm::dvec3(world[x][0], world[x][1], world[x][2]) + shift); // NaN stays NaN
			camera[x] = cv::Vec3f(v.x, v.y, v.z);
		}
	});
	const cv::Mat normals = compute_normal_map(vertices, p_max_jump_relative);
	io_maps->normals.create(vertices.size(), CV_32FC3);
	for_rows(vertices.rows, [&](int y) {
		const cv::Vec3f *camera = normals.ptr<cv::Vec3f>(y);
		cv::Vec3f *world = io_maps->normals.ptr<cv::Vec3f>(y);
		for (int x = 0; x < vertices.cols; ++x) {
			const glm::vec3 n(to_world * glm::dvec3(camera[x][0], camera[x][1], camera[x][2]));
			world[x] = cv::Vec3f(n.x, n.y, n.z);
		}
	});
}

cv::Mat intensity_of(const cv::Mat &p_rgb) {
	if (p_rgb.empty()) {
		return cv::Mat();
	}
	CV_Assert(p_rgb.type() == CV_8UC3);
	cv::Mat intensity(p_rgb.size(), CV_32FC1);
	for_rows(p_rgb.rows, [&](int y) {
		const cv::Vec3b *source = p_rgb.ptr<cv::Vec3b>(y);
		float *row = intensity.ptr<float>(y);
		for (int x = 0; x < p_rgb.cols; ++x) {
			row[x] = (float(source[x][0]) + float(source[x][1]) + float(source[x][2])) * (1.0f / (3.0f * 255.0f));
		}
	});
	return intensity;
}

FramePyramid build_frame_pyramid(const cv::Mat &p_clean_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, int p_levels,
		float p_band_m, const SurfaceOptions &p_surface, int p_finest_stride) {
	FramePyramid pyramid;
	for (int level = 0; level < p_levels; ++level) {
		const PinholeIntrinsics camera = p_camera.level(level);
		const cv::Mat depth = level == 0 ? smooth_depth(p_clean_depth_m, p_surface.smoothing_radius_px, p_surface.smoothing_band_m)
										 : downsample_depth(pyramid.depth.back(), p_band_m);
		CV_Assert(depth.cols == camera.width && depth.rows == camera.height);
		pyramid.cameras.push_back(camera);
		pyramid.depth.push_back(depth);
		pyramid.vertices.push_back(compute_vertex_map(depth, camera));
		pyramid.normals.push_back(compute_normal_map(pyramid.vertices.back(), p_surface.max_jump_relative, level == 0 ? p_finest_stride : 1));
		if (!p_rgb.empty()) {
			cv::Mat intensity = level == 0 ? intensity_of(p_rgb) : cv::Mat();
			if (level > 0) {
				// INTER_AREA at exactly half the size is the 2x2 mean, the blocks the depth uses.
				cv::resize(pyramid.intensity.back(), intensity, depth.size(), 0.0, 0.0, cv::INTER_AREA);
			}
			pyramid.intensity.push_back(intensity);
		}
	}
	return pyramid;
}

double normal_spread(const cv::Mat &p_normals) {
	CV_Assert(p_normals.empty() || p_normals.type() == CV_32FC3);
	double sum = 0.0;
	long long count = 0;
	for (int y = 1; y + 1 < p_normals.rows; y++) {
		for (int x = 1; x + 1 < p_normals.cols; x++) {
			cv::Vec3f mean(0.0f, 0.0f, 0.0f);
			bool whole = true;
			for (int dy = -1; dy <= 1 && whole; dy++) {
				const cv::Vec3f *row = p_normals.ptr<cv::Vec3f>(y + dy);
				for (int dx = -1; dx <= 1; dx++) {
					const cv::Vec3f &m = row[x + dx];
					whole = whole && m[0] == m[0]; // false for NaN
					mean += m;
				}
			}
			if (!whole) {
				continue;
			}
			const cv::Vec3f d = p_normals.at<cv::Vec3f>(y, x) - mean * (1.0f / 9.0f);
			sum += double(d.dot(d));
			count++;
		}
	}
	return count > 0 ? sum / double(count) : 0.0;
}

} // namespace roomprobe
