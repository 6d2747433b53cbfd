// TsdfVolume's raycasts (tsdf_volume.h): the depth range each cell of the image can hold a
// surface in (from the allocated blocks), the rays marched within it, and point samples of the
// model. Split from tsdf_volume.cpp to keep each file short.
#include "tsdf_volume.h"

#include "tsdf_raycast_gpu.h"
#include "tsdf_volume_internal.h"

#include <parallel/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace roomprobe {

using tsdf_volume_internal::rotation_matrix;

// ---- raycast ----

namespace {

constexpr int RANGE_CELL = TsdfVolume::DEPTH_RANGE_CELL_PX;

// One image row's outputs and its limits.
struct RowRays {
	cv::Vec3f *points;
	cv::Vec3f *normals;
	cv::Vec3b *colors;
	float *depth;
	const cv::Vec2f *ranges; // the row's depth-range cells
	const cv::Vec2f *search; // per pixel, or null
};

// Rays marched together on one thread: a sample of each in turn, each asking for its next
// sample's memory before the others step (tsdf_ray_prefetch). One ray at a time waited on the
// voxel pool at nearly every sample (a profile put 45 % of the march on two loads).
constexpr int RAY_LANES = 16;

// The pixels of row p_v marched RAY_LANES at a time; each ray is marched exactly as alone.
void march_row(const TsdfView &p_view, const TsdfRayParams &p_ray, const PinholeIntrinsics &p_camera, int p_v, const RowRays &p_row, long long *io_steps, int *io_hits) {
	struct Lane {
		TsdfRayMarch march;
		TsdfRayParams ray;
		int u = -1;
	};
	Lane lanes[RAY_LANES];
	int next_u = 0;
	// The next pixel of the row whose ray has something to march through, begun in p_lane.
	auto begin_next = [&](Lane *p_lane) {
		while (next_u < p_camera.width) {
			const int u = next_u++;
			cv::Vec2f range = p_row.ranges[u / RANGE_CELL];
			if (p_row.search != nullptr && std::isfinite(p_row.search[u][0]) && std::isfinite(p_row.search[u][1])) {
				range = cv::Vec2f(std::max(range[0], p_row.search[u][0]), std::min(range[1], p_row.search[u][1]));
			}
			if (!(range[0] <= range[1])) {
				continue; // no block projects here
			}
			p_lane->ray = p_ray;
			p_lane->ray.min_depth_m = std::max(p_ray.min_depth_m, range[0]);
			p_lane->ray.max_depth_m = std::min(p_ray.max_depth_m, range[1]);
			if (tsdf_ray_begin(p_lane->ray, p_camera, p_view.voxel_size, u, p_v, &p_lane->march)) {
				p_lane->u = u;
				tsdf_ray_prefetch(p_view, &p_lane->march);
				return;
			}
		}
		p_lane->u = -1;
	};
	int active = 0;
	for (Lane &lane : lanes) {
		begin_next(&lane);
		active += lane.u >= 0 ? 1 : 0;
	}
	while (active > 0) {
		for (Lane &lane : lanes) {
			if (lane.u < 0) {
				continue;
			}
			TsdfRayHit hit;
			const TsdfRayStatus status = tsdf_ray_step(p_view, lane.ray, &lane.march, &hit);
			if (status == TsdfRayStatus::Marching) {
				tsdf_ray_prefetch(p_view, &lane.march);
				continue;
			}
			*io_steps += lane.march.steps;
			if (status == TsdfRayStatus::Hit) {
				const int u = lane.u;
				(*io_hits)++;
				p_row.points[u] = cv::Vec3f(hit.point.x, hit.point.y, hit.point.z);
				p_row.normals[u] = cv::Vec3f(hit.normal.x, hit.normal.y, hit.normal.z);
				p_row.colors[u] = cv::Vec3b(cv::saturate_cast<uint8_t>(hit.rgb.x), cv::saturate_cast<uint8_t>(hit.rgb.y), cv::saturate_cast<uint8_t>(hit.rgb.z));
				p_row.depth[u] = hit.depth;
			}
			begin_next(&lane);
			active -= lane.u < 0 ? 1 : 0;
		}
	}
}

} // namespace

cv::Mat TsdfVolume::depth_ranges(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_near_m, float p_far_m) const {
	// Rays start at the first block they can meet and stop after the last, and cells no block
	// covers are not marched at all.
	const int cols = (p_camera.width + RANGE_CELL - 1) / RANGE_CELL, rows = (p_camera.height + RANGE_CELL - 1) / RANGE_CELL;
	const cv::Scalar empty(std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity());
	const Pose camera_from_world = inverse(p_world_from_camera);
	const glm::mat3 rotation = rotation_matrix(camera_from_world);
	const glm::vec3 translation(camera_from_world.translation);
	const float block_m = float(TSDF_BLOCK_SIDE) * m_options.voxel_size_m;
	const float radius = 0.5f * std::sqrt(3.0f) * block_m;
	const float near = p_near_m;
	// Slots in chunks, each into its own image, merged after (min and max: the same result in any
	// order).
	constexpr int CHUNKS = 8;
	const size_t slots = m_slot_block.size();
	std::vector<cv::Mat> partial(CHUNKS);
	parallel_for(cv::Range(0, CHUNKS), [&](const cv::Range &p_range) {
		for (int k = p_range.start; k < p_range.end; k++) {
			cv::Mat &ranges = partial[size_t(k)];
			ranges.create(rows, cols, CV_32FC2);
			ranges.setTo(empty);
			for (size_t s = slots * size_t(k) / CHUNKS; s < slots * size_t(k + 1) / CHUNKS; s++) {
				if (!m_slot_used[s]) {
					continue;
				}
				// The region whose nearest voxels are this block's: [8 b - 0.5, 8 b + 7.5) voxels.
				const glm::vec3 lo = glm::vec3(m_slot_block[s]) * block_m - glm::vec3(0.5f * m_options.voxel_size_m);
				// Most blocks lie outside the view: rejected by their bounding sphere (conservatively,
				// with a pixel's margin) before their corners are projected.
				const glm::vec3 centre = rotation * (lo + glm::vec3(0.5f * block_m)) + translation;
				if (centre.z + radius < near || centre.z - radius > p_far_m) {
					continue;
				}
				if (centre.z - radius > near) {
					const float z0 = centre.z - radius, z1 = centre.z + radius;
					const float x_lo = p_camera.fx * std::min((centre.x - radius) / z0, (centre.x - radius) / z1) + p_camera.cx - 1.0f;
					const float x_hi = p_camera.fx * std::max((centre.x + radius) / z0, (centre.x + radius) / z1) + p_camera.cx + 1.0f;
					const float y_lo = p_camera.fy * std::min((centre.y - radius) / z0, (centre.y - radius) / z1) + p_camera.cy - 1.0f;
					const float y_hi = p_camera.fy * std::max((centre.y + radius) / z0, (centre.y + radius) / z1) + p_camera.cy + 1.0f;
					// Cells are found by truncating division below: pixels down to -RANGE_CELL land in cell 0.
					if (x_hi < -float(RANGE_CELL) || y_hi < -float(RANGE_CELL) || x_lo >= float(cols * RANGE_CELL) || y_lo >= float(rows * RANGE_CELL)) {
						continue;
					}
				}
				float zmin = std::numeric_limits<float>::infinity(), zmax = -zmin;
				glm::vec2 pmin(std::numeric_limits<float>::infinity()), pmax(-std::numeric_limits<float>::infinity());
				bool straddles = false;
				for (int c = 0; c < 8; c++) {
					const glm::vec3 corner = lo + glm::vec3(float(c & 1), float((c >> 1) & 1), float((c >> 2) & 1)) * block_m;
					const glm::vec3 pc = rotation * corner + translation;
					zmin = std::min(zmin, pc.z);
					zmax = std::max(zmax, pc.z);
					glm::vec2 pixel;
					if (pc.z < near || !p_camera.project(pc, &pixel)) {
						straddles = true;
						continue;
					}
					pmin = glm::min(pmin, pixel);
					pmax = glm::max(pmax, pixel);
				}
				if (zmax < near || zmin > p_far_m) {
					continue;
				}
				if (straddles) {
					// A corner before the near plane: the block may cover any pixel.
					pmin = glm::vec2(0.0f);
					pmax = glm::vec2(float(p_camera.width - 1), float(p_camera.height - 1));
				}
				const int c0 = std::max(0, int(std::floor(pmin.x)) / RANGE_CELL), c1 = std::min(cols - 1, int(std::floor(pmax.x)) / RANGE_CELL);
				const int r0 = std::max(0, int(std::floor(pmin.y)) / RANGE_CELL), r1 = std::min(rows - 1, int(std::floor(pmax.y)) / RANGE_CELL);
				for (int r = r0; r <= r1; r++) {
					cv::Vec2f *row = ranges.ptr<cv::Vec2f>(r);
					for (int c = c0; c <= c1; c++) {
						row[c][0] = std::min(row[c][0], zmin);
						row[c][1] = std::max(row[c][1], zmax);
					}
				}
			}
		}
	});
	cv::Mat ranges = partial[0];
	for (int k = 1; k < CHUNKS; k++) {
		for (int r = 0; r < rows; r++) {
			cv::Vec2f *out = ranges.ptr<cv::Vec2f>(r);
			const cv::Vec2f *in = partial[size_t(k)].ptr<cv::Vec2f>(r);
			for (int c = 0; c < cols; c++) {
				out[c][0] = std::min(out[c][0], in[c][0]);
				out[c][1] = std::max(out[c][1], in[c][1]);
			}
		}
	}
	return ranges;
}

void TsdfVolume::raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, ModelMaps *r_maps, RaycastStats *r_stats) const {
	raycast(p_camera, p_world_from_camera, m_options.min_depth_m, m_options.max_depth_m, r_maps, r_stats);
}

void TsdfVolume::raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_min_depth_m, float p_max_depth_m, ModelMaps *r_maps,
		RaycastStats *r_stats, bool p_normals) const {
	raycast_ranged(p_camera, p_world_from_camera, p_min_depth_m, p_max_depth_m, nullptr, p_normals, r_maps, r_stats);
}

void TsdfVolume::raycast(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, const cv::Mat &p_search_m, ModelMaps *r_maps,
		RaycastStats *r_stats, bool p_normals) const {
	CV_Assert(p_search_m.type() == CV_32FC2 && p_search_m.cols == p_camera.width && p_search_m.rows == p_camera.height);
	raycast_ranged(p_camera, p_world_from_camera, m_options.min_depth_m, m_options.max_depth_m, &p_search_m, p_normals, r_maps, r_stats);
}

void TsdfVolume::raycast_ranged(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_min_depth_m, float p_max_depth_m,
		const cv::Mat *p_search_m, bool p_normals, ModelMaps *r_maps, RaycastStats *r_stats) const {
	const float nan = std::numeric_limits<float>::quiet_NaN();
	r_maps->camera = p_camera;
	r_maps->world_from_camera = p_world_from_camera;
	r_maps->points.create(p_camera.height, p_camera.width, CV_32FC3);
	r_maps->normals.create(p_camera.height, p_camera.width, CV_32FC3);
	r_maps->colors.create(p_camera.height, p_camera.width, CV_8UC3);
	r_maps->depth.create(p_camera.height, p_camera.width, CV_32FC1);
	// No surface anywhere until a ray finds one (the device writes every pixel itself).
	auto blank = [&]() {
		r_maps->points.setTo(cv::Scalar::all(nan));
		r_maps->normals.setTo(cv::Scalar::all(nan));
		r_maps->colors.setTo(cv::Scalar::all(0));
		r_maps->depth.setTo(cv::Scalar::all(nan));
	};
	RaycastStats stats;
	if (m_allocated == 0) {
		blank();
		if (r_stats != nullptr) {
			*r_stats = stats;
		}
		return;
	}
	const cv::Mat ranges = depth_ranges(p_camera, p_world_from_camera, p_min_depth_m, p_max_depth_m);
	if (m_gpu_raycaster && !m_gpu_raycaster->has_failed()) {
		TsdfRaycastInput input;
		input.camera = p_camera;
		input.world_from_camera = p_world_from_camera;
		input.min_depth_m = p_min_depth_m;
		input.max_depth_m = p_max_depth_m;
		input.bounds_min = m_bounds_min;
		input.bounds_max = m_bounds_max;
		input.normals = p_normals;
		input.ranges = &ranges;
		input.search_m = p_search_m;
		input.hash = m_hash.data();
		input.hash_mask = m_hash_mask;
		input.hash_version = m_hash_version;
		input.voxel_size_m = m_options.voxel_size_m;
		input.truncation_m = m_options.truncation_m;
		if (m_gpu_raycaster->raycast(input, r_maps, r_stats)) {
			return;
		}
		// Failed: the CPU casts this one and the rest, and compute_problem() says why.
		const std::lock_guard<std::mutex> lock(m_status->mutex);
		m_status->raycasting = false;
		m_status->raycast_problem = "the raycast on the GPU failed: " + m_gpu_raycaster->failure();
	}
	blank();
	const TsdfView view = this->view();
	TsdfRayParams ray;
	ray.origin = glm::vec3(p_world_from_camera.translation);
	ray.world_from_camera_rotation = rotation_matrix(p_world_from_camera);
	ray.min_depth_m = p_min_depth_m;
	ray.max_depth_m = p_max_depth_m;
	ray.bounds_min = m_bounds_min;
	ray.bounds_max = m_bounds_max;
	ray.normals = p_normals;
	std::vector<long long> steps(size_t(p_camera.height), 0);
	std::vector<int> hits(size_t(p_camera.height), 0);
	parallel_for(cv::Range(0, p_camera.height), [&](const cv::Range &p_range) {
		for (int v = p_range.start; v < p_range.end; v++) {
			RowRays row{ r_maps->points.ptr<cv::Vec3f>(v), r_maps->normals.ptr<cv::Vec3f>(v), r_maps->colors.ptr<cv::Vec3b>(v), r_maps->depth.ptr<float>(v),
				ranges.ptr<cv::Vec2f>(v / RANGE_CELL), p_search_m != nullptr ? p_search_m->ptr<cv::Vec2f>(v) : nullptr };
			march_row(view, ray, p_camera, v, row, &steps[size_t(v)], &hits[size_t(v)]);
		}
	});
	for (int v = 0; v < p_camera.height; v++) {
		stats.steps += steps[size_t(v)];
		stats.hit_pixels += hits[size_t(v)];
	}
	if (r_stats != nullptr) {
		*r_stats = stats;
	}
}

bool TsdfVolume::sample_tsdf(const glm::vec3 &p_world, float *r_tsdf, glm::vec3 *r_rgb) const {
	if (m_allocated == 0) {
		return false;
	}
	const TsdfView view = this->view();
	const glm::vec3 grid = p_world / m_options.voxel_size_m;
	TsdfBlockCache cache;
	if (!tsdf_trilinear(view, grid, &cache, r_tsdf)) {
		return false;
	}
	if (r_rgb != nullptr && !tsdf_trilinear_color(view, grid, &cache, r_rgb)) {
		*r_rgb = glm::vec3(0.0f);
	}
	return true;
}

} // namespace roomprobe
