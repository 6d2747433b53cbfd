#include "tsdf_raycast_gpu.h"

#include "tsdf_integrate_gpu.h"
#include "tsdf_volume.h"
#include "tsdf_volume_internal.h"

#include <spirv/tsdf_raycast.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace roomprobe {

namespace {

constexpr int HIT_FLOATS = 12; // tsdf_raycast.comp's

// tsdf_raycast.comp's Params, std430.
struct Params {
	float fx, fy, cx, cy;
	int32_t width, height, cells_x, has_search;
	float rotation[12];
	float origin[4];
	float bounds_min[4], bounds_max[4];
	float voxel_size, truncation, min_depth_m, max_depth_m;
	uint32_t hash_mask, window_blocks, normals, search_offset;
};
static_assert(sizeof(Params) == 40 * 4);
static_assert(sizeof(TsdfHashEntry) == 16, "tsdf_raycast.comp reads entries as ivec4");

// An interval as the kernel takes it: far < near where there is none (no infinity on the device).
cv::Vec2f device_interval(const cv::Vec2f &p_interval) {
	return std::isfinite(p_interval[0]) && std::isfinite(p_interval[1]) ? p_interval : cv::Vec2f(1.0f, 0.0f);
}

} // namespace

std::unique_ptr<TsdfRaycasterGpu> TsdfRaycasterGpu::create(const TsdfIntegratorGpu &p_pool, std::string *r_error) {
	const size_t windows = p_pool.pool_windows();
	if (windows > size_t(MAX_WINDOWS)) {
		*r_error = "the voxel pool spans " + std::to_string(windows) + " bindings of the device's largest storage buffer; the raycast binds at most " +
				std::to_string(MAX_WINDOWS) + ": lower max_blocks";
		return nullptr;
	}
	std::unique_ptr<TsdfRaycasterGpu> out(new TsdfRaycasterGpu(p_pool));
	out->kernel = p_pool.device().make_kernel(spirv::tsdf_raycast, sizeof(spirv::tsdf_raycast) / sizeof(uint32_t), 8, 0, r_error, "tsdf_raycast");
	if (!out->kernel || !p_pool.device().ensure_buffer(&out->params, sizeof(Params), GpuAccess::DeviceReads, r_error)) {
		return nullptr;
	}
	return out;
}

bool TsdfRaycasterGpu::raycast(const TsdfRaycastInput &p_input, ModelMaps *r_maps, RaycastStats *r_stats) const {
	const std::lock_guard<std::mutex> lock(busy);
	if (!failed_because.empty()) {
		return false;
	}
	std::string error;
	if (!run(p_input, r_maps, r_stats, &error)) {
		failed_because = error.empty() ? "the raycast failed" : error;
		return false;
	}
	return true;
}

bool TsdfRaycasterGpu::has_failed() const {
	const std::lock_guard<std::mutex> lock(busy);
	return !failed_because.empty();
}

std::string TsdfRaycasterGpu::failure() const {
	const std::lock_guard<std::mutex> lock(busy);
	return failed_because;
}

bool TsdfRaycasterGpu::run(const TsdfRaycastInput &p_input, ModelMaps *r_maps, RaycastStats *r_stats, std::string *r_error) const {
	const ComputeDevice &device = pool.device();
	const PinholeIntrinsics &camera = p_input.camera;
	const size_t pixels = size_t(camera.width) * size_t(camera.height);
	const cv::Mat &cells = *p_input.ranges;
	const size_t cell_count = size_t(cells.rows) * size_t(cells.cols);
	const size_t intervals = cell_count + (p_input.search_m != nullptr ? pixels : 0);
	const size_t hash_entries = size_t(p_input.hash_mask) + 1;
	if (!device.ensure_buffer(&hash, hash_entries * sizeof(TsdfHashEntry), GpuAccess::DeviceReads, r_error) ||
			!device.ensure_buffer(&ranges, intervals * sizeof(cv::Vec2f), GpuAccess::DeviceReads, r_error) ||
			!device.ensure_buffer(&hits, pixels * HIT_FLOATS * sizeof(float), GpuAccess::HostReads, r_error)) {
		return false;
	}
	if (uploaded_version != p_input.hash_version) {
		std::memcpy(hash->data(), p_input.hash, hash_entries * sizeof(TsdfHashEntry));
		uploaded_version = p_input.hash_version;
	}
	cv::Vec2f *interval = static_cast<cv::Vec2f *>(ranges->data());
	for (int r = 0; r < cells.rows; r++) {
		for (int c = 0; c < cells.cols; c++) {
			*interval++ = device_interval(cells.at<cv::Vec2f>(r, c));
		}
	}
	for (int v = 0; p_input.search_m != nullptr && v < camera.height; v++) {
		for (int u = 0; u < camera.width; u++) {
			*interval++ = device_interval(p_input.search_m->at<cv::Vec2f>(v, u));
		}
	}
	Params p{};
	p.fx = camera.fx, p.fy = camera.fy, p.cx = camera.cx, p.cy = camera.cy;
	p.width = camera.width, p.height = camera.height, p.cells_x = cells.cols, p.has_search = p_input.search_m != nullptr ? 1 : 0;
	const glm::mat3 rotation = tsdf_volume_internal::rotation_matrix(p_input.world_from_camera);
	for (int c = 0; c < 3; c++) {
		for (int k = 0; k < 3; k++) {
			p.rotation[4 * c + k] = rotation[c][k];
		}
	}
	const glm::vec3 origin(p_input.world_from_camera.translation);
	for (int k = 0; k < 3; k++) {
		p.origin[k] = origin[k];
		p.bounds_min[k] = p_input.bounds_min[k];
		p.bounds_max[k] = p_input.bounds_max[k];
	}
	p.voxel_size = p_input.voxel_size_m, p.truncation = p_input.truncation_m;
	p.min_depth_m = p_input.min_depth_m, p.max_depth_m = p_input.max_depth_m;
	p.hash_mask = p_input.hash_mask, p.window_blocks = uint32_t(pool.blocks_per_window());
	p.normals = p_input.normals ? 1u : 0u, p.search_offset = uint32_t(cell_count);
	std::memcpy(params->data(), &p, sizeof(p));

	GpuDispatch dispatch;
	dispatch.kernel = kernel.get();
	const GpuBuffer *voxels = &pool.pool_buffer();
	dispatch.buffers = { voxels, voxels, voxels, voxels, hash.get(), ranges.get(), hits.get(), params.get() };
	for (size_t w = 0; w < size_t(MAX_WINDOWS); w++) {
		dispatch.windows.push_back(pool.pool_window(w < pool.pool_windows() ? w : 0)); // windows past the pool: the first again, unread
	}
	dispatch.groups_x = uint32_t((camera.width + 7) / 8);
	dispatch.groups_y = uint32_t((camera.height + 7) / 8);
	*r_error = device.run({ dispatch });
	if (!r_error->empty()) {
		return false;
	}

	const float nan = std::numeric_limits<float>::quiet_NaN();
	r_maps->camera = camera;
	r_maps->world_from_camera = p_input.world_from_camera;
	r_maps->points.create(camera.height, camera.width, CV_32FC3);
	r_maps->normals.create(camera.height, camera.width, CV_32FC3);
	r_maps->colors.create(camera.height, camera.width, CV_8UC3);
	r_maps->depth.create(camera.height, camera.width, CV_32FC1);
	RaycastStats stats;
	const float *hit = static_cast<const float *>(hits->data());
	for (int v = 0; v < camera.height; v++) {
		cv::Vec3f *points = r_maps->points.ptr<cv::Vec3f>(v);
		cv::Vec3f *normals = r_maps->normals.ptr<cv::Vec3f>(v);
		cv::Vec3b *colors = r_maps->colors.ptr<cv::Vec3b>(v);
		float *depth = r_maps->depth.ptr<float>(v);
		for (int u = 0; u < camera.width; u++, hit += HIT_FLOATS) {
			uint32_t steps;
			std::memcpy(&steps, &hit[10], sizeof(steps));
			stats.steps += steps;
			if (!(hit[3] > 0.0f)) {
				points[u] = normals[u] = cv::Vec3f(nan, nan, nan);
				colors[u] = cv::Vec3b(0, 0, 0);
				depth[u] = nan;
				continue;
			}
			stats.hit_pixels++;
			points[u] = cv::Vec3f(hit[0], hit[1], hit[2]);
			depth[u] = hit[3];
			normals[u] = p_input.normals ? cv::Vec3f(hit[4], hit[5], hit[6]) : cv::Vec3f(nan, nan, nan);
			colors[u] = cv::Vec3b(cv::saturate_cast<uint8_t>(hit[7]), cv::saturate_cast<uint8_t>(hit[8]), cv::saturate_cast<uint8_t>(hit[9]));
		}
	}
	if (r_stats != nullptr) {
		*r_stats = stats;
	}
	return true;
}

} // namespace roomprobe
