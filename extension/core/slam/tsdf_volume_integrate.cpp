// TsdfVolume's integration of a frame (tsdf_volume.h): the blocks along the readings' bands,
// the allocated blocks in view, room for the new ones, and the update of their voxels, culling
// the blocks no update could change. Split from tsdf_volume.cpp to keep each file short.
#include "tsdf_volume.h"

#include "depth_pyramid.h"
#include "tsdf_integrate_gpu.h"
#include "tsdf_integrate_simd.h"

#include <parallel/parallel_for.h>
#include "tsdf_volume_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace roomprobe {

using tsdf_volume_internal::block_centre;
using tsdf_volume_internal::rotation_matrix;

namespace {

// Rows per parallel_for_ stripe: enough work per task, and a fixed split.
constexpr int ROWS_PER_STRIPE = 8;

// The last few blocks appended, as packed keys: neighbouring pixels mostly share blocks, and one
// 64-bit compare per entry is cheaper than looking back through the vector.
struct RecentBlocks {
	static constexpr int SIZE = 8;
	uint64_t keys[SIZE] = {};
	int next = 0;
	bool used[SIZE] = {};

	// True when p_block was among the last SIZE; else remembers it.
	bool seen_or_add(const glm::ivec3 &p_block) {
		const uint64_t k = tsdf_block_key(p_block);
		if (k == keys[(next + SIZE - 1) % SIZE] && used[(next + SIZE - 1) % SIZE]) {
			return true; // the last one: mostly, for neighbouring pixels
		}
		for (int i = 0; i < SIZE; i++) {
			if (used[i] && keys[i] == k) {
				return true;
			}
		}
		keys[next] = k;
		used[next] = true;
		next = (next + 1) % SIZE;
		return false;
	}
};

// Appends the blocks (in block units) a segment passes through, by a 3D DDA (Amanatides & Woo),
// skipping those among the last few appended (p_recent). Block coordinates stay far below 2^31.
void append_segment_blocks(const glm::vec3 &p_a, const glm::vec3 &p_b, RecentBlocks *p_recent, std::vector<glm::ivec3> *r_blocks) {
	glm::ivec3 cell(tsdf_floor(p_a.x), tsdf_floor(p_a.y), tsdf_floor(p_a.z));
	const glm::ivec3 last(tsdf_floor(p_b.x), tsdf_floor(p_b.y), tsdf_floor(p_b.z));
	// Most bands (8 cm at the defaults, a block's size) lie in one block or in two that share a
	// face: their union is a box, so the segment meets those two and no other, without the DDA.
	const glm::ivec3 apart = glm::abs(last - cell);
	if (apart.x + apart.y + apart.z <= 1) {
		if (!p_recent->seen_or_add(cell)) {
			r_blocks->push_back(cell);
		}
		if (last != cell && !p_recent->seen_or_add(last)) {
			r_blocks->push_back(last);
		}
		return;
	}
	const glm::vec3 d = p_b - p_a;
	glm::ivec3 step(0);
	glm::vec3 t_max(std::numeric_limits<float>::infinity());
	glm::vec3 t_delta(std::numeric_limits<float>::infinity());
	for (int a = 0; a < 3; a++) {
		if (d[a] > 0.0f) {
			step[a] = 1;
			t_max[a] = (float(cell[a] + 1) - p_a[a]) / d[a];
			t_delta[a] = 1.0f / d[a];
		} else if (d[a] < 0.0f) {
			step[a] = -1;
			t_max[a] = (float(cell[a]) - p_a[a]) / d[a];
			t_delta[a] = -1.0f / d[a];
		}
	}
	for (int guard = 0; guard < 64; guard++) {
		if (!p_recent->seen_or_add(cell)) {
			r_blocks->push_back(cell);
		}
		if (cell == last) {
			break;
		}
		const int a = t_max.x < t_max.y ? (t_max.x < t_max.z ? 0 : 2) : (t_max.y < t_max.z ? 1 : 2);
		if (t_max[a] > 1.0f) {
			break;
		}
		cell[a] += step[a];
		t_max[a] += t_delta[a];
	}
}

// Pixels per side of a tile of the depth-bounds grid that integration culls blocks with.
constexpr int DEPTH_TILE = 8;

// Per tile of DEPTH_TILE^2 pixels, [min, max] of the usable readings (+inf, -inf when none).
struct DepthTiles {
	int cols = 0, rows = 0;
	std::vector<glm::vec2> bounds;
};

DepthTiles depth_tiles(const cv::Mat &p_depth_m, float p_min_depth_m, float p_max_depth_m) {
	DepthTiles tiles;
	tiles.cols = (p_depth_m.cols + DEPTH_TILE - 1) / DEPTH_TILE;
	tiles.rows = (p_depth_m.rows + DEPTH_TILE - 1) / DEPTH_TILE;
	const float inf = std::numeric_limits<float>::infinity();
	tiles.bounds.assign(size_t(tiles.cols) * size_t(tiles.rows), glm::vec2(inf, -inf));
	parallel_for(cv::Range(0, tiles.rows), [&](const cv::Range &p_range) {
		for (int r = p_range.start; r < p_range.end; r++) {
			glm::vec2 *out = &tiles.bounds[size_t(r) * size_t(tiles.cols)];
			for (int v = r * DEPTH_TILE; v < std::min(p_depth_m.rows, (r + 1) * DEPTH_TILE); v++) {
				const float *row = p_depth_m.ptr<float>(v);
				for (int u = 0; u < p_depth_m.cols; u++) {
					const float d = row[u];
					if (tsdf_depth_valid(d, p_min_depth_m, p_max_depth_m)) {
						glm::vec2 &b = out[u / DEPTH_TILE];
						b.x = std::min(b.x, d);
						b.y = std::max(b.y, d);
					}
				}
			}
		}
	});
	return tiles;
}

// Whether an update of a block's voxels could change any of them, from the readings its
// voxels can reach (the tiles under its projection, widened by the pixel that rounding and the
// bilinear depth add). p_origin: voxel (0, 0, 0) of the block in the camera's frame; p_step_*:
// one voxel along the grid's axes there. The tests mirror tsdf_update_voxel_at's own exits.
bool block_may_change(const TsdfFrameView &p_frame, const DepthTiles &p_tiles, const glm::vec3 &p_origin, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y,
		const glm::vec3 &p_step_z, bool p_saturated) {
	const float last = float(TSDF_BLOCK_SIDE - 1);
	float zmin = std::numeric_limits<float>::infinity(), zmax = -zmin;
	glm::vec2 pmin(std::numeric_limits<float>::infinity()), pmax(-std::numeric_limits<float>::infinity());
	for (int c = 0; c < 8; c++) {
		const glm::vec3 pc = p_origin + (c & 1 ? last : 0.0f) * p_step_x + ((c >> 1) & 1 ? last : 0.0f) * p_step_y + ((c >> 2) & 1 ? last : 0.0f) * p_step_z;
		glm::vec2 pixel;
		if (!(pc.z > 1e-3f) || !p_frame.camera.project(pc, &pixel)) {
			return true; // the block reaches the camera's plane: no bound on its pixels
		}
		zmin = std::min(zmin, pc.z);
		zmax = std::max(zmax, pc.z);
		pmin = glm::min(pmin, pixel);
		pmax = glm::max(pmax, pixel);
	}
	// The voxels' nearest pixels and bilinear neighbours lie in [floor(min), floor(max) + 1]; one
	// pixel more on each side for rounding.
	pmin -= glm::vec2(1.0f);
	pmax += glm::vec2(2.0f);
	const float w = float(p_frame.camera.width), h = float(p_frame.camera.height);
	if (!(pmax.x >= 0.0f && pmax.y >= 0.0f && pmin.x < w && pmin.y < h)) {
		return false; // wholly off the image
	}
	const int u0 = std::max(0, int(std::floor(pmin.x))), u1 = std::min(p_frame.camera.width - 1, int(std::floor(pmax.x)));
	const int v0 = std::max(0, int(std::floor(pmin.y))), v1 = std::min(p_frame.camera.height - 1, int(std::floor(pmax.y)));
	float dmin = std::numeric_limits<float>::infinity(), dmax = -dmin;
	for (int r = v0 / DEPTH_TILE; r <= v1 / DEPTH_TILE; r++) {
		const glm::vec2 *row = &p_tiles.bounds[size_t(r) * size_t(p_tiles.cols)];
		for (int c = u0 / DEPTH_TILE; c <= u1 / DEPTH_TILE; c++) {
			dmin = std::min(dmin, row[c].x);
			dmax = std::max(dmax, row[c].y);
		}
	}
	if (!(dmin <= dmax)) {
		return false; // no reading under the block
	}
	// The stepped voxel points and the corners differ by rounding only: a margin of 0.1 mm.
	constexpr float MARGIN_M = 1e-4f;
	if (dmax - (zmin - MARGIN_M) < -p_frame.behind_limit_m) {
		return false; // wholly well behind the readings
	}
	if (p_saturated && p_frame.min_slope > 0.0f) {
		// Wholly in free space (eta >= its lower bound for every voxel: the bilinear depth is never
		// below the smallest reading) and already at +1 with the full weight: nothing changes.
		const float eta_lo = (dmin - (zmax + MARGIN_M)) * std::min(p_frame.min_slope, 1.0f);
		if (eta_lo >= p_frame.truncation_m && eta_lo >= p_frame.color_band_m) {
			return false;
		}
	}
	return true;
}

// The frame as the voxel updates read it (tsdf_kernels.h): its pose, its clean depth p_depth,
// its colour and the options; the slope factors are set by add_slope_factors.
TsdfFrameView integration_frame(const cv::Mat &p_depth, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera,
		const TsdfOptions &p_options) {
	const Pose camera_from_world = inverse(p_world_from_camera);
	TsdfFrameView frame;
	frame.camera = p_camera;
	frame.camera_from_world_rotation = rotation_matrix(camera_from_world);
	frame.camera_from_world_translation = glm::vec3(camera_from_world.translation);
	frame.depth = p_depth.ptr<float>(0);
	frame.depth_stride = p_depth.step1();
	frame.rgb = p_rgb.ptr<uint8_t>(0);
	frame.rgb_stride = p_rgb.step[0];
	frame.truncation_m = p_options.truncation_m;
	frame.color_band_m = p_options.color_band_m;
	frame.min_depth_m = p_options.min_depth_m;
	frame.max_depth_m = p_options.max_depth_m;
	frame.behind_limit_m = tsdf_behind_limit(p_options.truncation_m, p_options.min_slope);
	frame.max_weight = uint16_t(p_options.max_weight);
	frame.max_color_weight = uint16_t(std::clamp(p_options.max_color_weight, 1, 65535));
	frame.min_slope = p_options.min_slope;
	frame.early_exits = p_options.skip_unchanged;
	return frame;
}

// The slope factors of the frame's pixels (tsdf_depth_slope) into r_slope, which r_frame then
// points to: keep it with it. A depth jump of half the band between neighbours is an edge. Taken
// on the depth smoothed as ICP smooths it: a sensor's noise (centimetres at 3 m) over one-pixel
// differences (6 mm there) would tilt the tangent planes at random and reject most far readings
// as grazing. (The device makes its own: TsdfIntegratorGpu.)
void add_slope_factors(const cv::Mat &p_depth, const TsdfOptions &p_options, TsdfFrameView *r_frame, cv::Mat *r_slope) {
	const PinholeIntrinsics &camera = r_frame->camera;
	const cv::Mat smoothed = p_options.slope_smoothing_px > 0 ? smooth_depth(p_depth, p_options.slope_smoothing_px, p_options.truncation_m) : p_depth;
	cv::Mat &slope = *r_slope;
	slope.create(p_depth.size(), CV_32FC1);
	const float *smoothed_data = smoothed.ptr<float>(0);
	const size_t smoothed_stride = smoothed.step1();
	parallel_for(cv::Range(0, p_depth.rows), [&](const cv::Range &p_range) {
		for (int v = p_range.start; v < p_range.end; v++) {
			float *row = slope.ptr<float>(v);
			for (int u = 0; u < p_depth.cols; u++) {
				row[u] = tsdf_depth_slope(smoothed_data, smoothed_stride, camera, u, v, 0.5f * p_options.truncation_m);
			}
		}
	});
	r_frame->slope = slope.ptr<float>(0);
	r_frame->slope_stride = slope.step1();
}

// Updates the voxels of one block, p_voxel its first, row by row from p_origin (its voxel
// (0, 0, 0) in the camera's frame) by the steps; true when any changed. r_saturated: whether
// every voxel is now at +1 with p_full_weight.
bool update_block_voxels(const TsdfFrameView &p_frame, const glm::vec3 &p_origin, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y,
		const glm::vec3 &p_step_z, bool p_simd, uint16_t p_full_weight, TsdfVoxel *p_voxel, bool *r_saturated) {
	TsdfVoxel *voxel = p_voxel;
	bool any = false;
	bool saturated = true;
	for (int z = 0; z < TSDF_BLOCK_SIDE; z++) {
		for (int y = 0; y < TSDF_BLOCK_SIDE; y++, voxel += TSDF_BLOCK_SIDE) {
			const glm::vec3 row = p_origin + float(y) * p_step_y + float(z) * p_step_z;
			if (p_simd) {
				any |= tsdf_update_row_simd(p_frame, row, p_step_x, voxel);
			} else {
				for (int x = 0; x < TSDF_BLOCK_SIDE; x++) {
					any |= tsdf_update_voxel_at(p_frame, row + float(x) * p_step_x, voxel + x);
				}
			}
			for (int x = 0; x < TSDF_BLOCK_SIDE && saturated; x++) { // a block near a surface stops at its first row
				saturated = voxel[x].tsdf == 1.0f && voxel[x].weight == p_full_weight;
			}
		}
	}
	*r_saturated = saturated;
	return any;
}

} // namespace

// ---- integration ----

void TsdfVolume::collect_band_blocks(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, std::vector<glm::ivec3> *r_blocks, int *r_valid_pixels) const {
	const glm::mat3 rotation = rotation_matrix(p_world_from_camera);
	const glm::vec3 translation(p_world_from_camera.translation);
	const float inv_block = 1.0f / (m_options.voxel_size_m * float(TSDF_BLOCK_SIDE));
	const int stripes = (p_depth_m.rows + ROWS_PER_STRIPE - 1) / ROWS_PER_STRIPE;
	std::vector<std::vector<glm::ivec3>> per_stripe(static_cast<size_t>(stripes));
	std::vector<int> valid(size_t(stripes), 0);
	// A pixel's ray in block units, per metre of camera z: row_ray + u * ray_step (no division a pixel).
	const glm::vec3 origin = translation * inv_block;
	const glm::vec3 ray_step = rotation[0] * (inv_block / p_camera.fx); // glm: [0] is column 0
	parallel_for(cv::Range(0, stripes), [&](const cv::Range &p_range) {
		for (int s = p_range.start; s < p_range.end; s++) {
			std::vector<glm::ivec3> &out = per_stripe[size_t(s)];
			RecentBlocks recent;
			for (int v = s * ROWS_PER_STRIPE; v < std::min(p_depth_m.rows, (s + 1) * ROWS_PER_STRIPE); v++) {
				const float *row = p_depth_m.ptr<float>(v);
				const glm::vec3 row_ray = rotation * p_camera.unproject(glm::vec2(0.0f, float(v)), 1.0f) * inv_block;
				for (int u = 0; u < p_depth_m.cols; u++) {
					const float d = row[u];
					if (!(d == d)) {
						continue; // no reading (the depth is clean)
					}
					valid[size_t(s)]++;
					const glm::vec3 ray = row_ray + float(u) * ray_step;
					const float z0 = std::max(d - m_options.truncation_m, 0.5f * m_options.min_depth_m);
					append_segment_blocks(origin + z0 * ray, origin + (d + m_options.truncation_m) * ray, &recent, &out);
				}
			}
		}
	});
	*r_valid_pixels = 0;
	r_blocks->clear();
	for (int s = 0; s < stripes; s++) {
		*r_valid_pixels += valid[size_t(s)];
		r_blocks->insert(r_blocks->end(), per_stripe[size_t(s)].begin(), per_stripe[size_t(s)].end());
	}
}

void TsdfVolume::mark_blocks_in_view(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera) {
	// Allocated blocks that project into the image (with a margin of the block's radius) are
	// updated too: free space seen through them carves them towards +1. Not those wholly behind
	// the reading at their centre's pixel (beyond the band): no voxel of theirs would change, and
	// in a room most blocks in the frustum are hidden behind the nearer surfaces.
	const Pose camera_from_world = inverse(p_world_from_camera);
	const glm::mat3 rotation = rotation_matrix(camera_from_world);
	const glm::vec3 translation(camera_from_world.translation);
	const float radius = 0.5f * std::sqrt(3.0f) * float(TSDF_BLOCK_SIDE) * m_options.voxel_size_m;
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (!m_slot_used[s] || m_slot_frame[s] == m_frame) {
			continue;
		}
		const glm::vec3 pc = rotation * block_centre(m_slot_block[s], m_options.voxel_size_m) + translation;
		if (pc.z + radius < m_options.min_depth_m || pc.z - radius > m_options.max_depth_m + m_options.truncation_m) {
			continue;
		}
		glm::vec2 pixel;
		if (!p_camera.project(glm::vec3(pc.x, pc.y, std::max(pc.z, m_options.min_depth_m)), &pixel)) {
			continue;
		}
		const float margin_x = radius * p_camera.fx / std::max(pc.z, m_options.min_depth_m);
		const float margin_y = radius * p_camera.fy / std::max(pc.z, m_options.min_depth_m);
		if (pixel.x >= -margin_x && pixel.y >= -margin_y && pixel.x <= float(p_camera.width) + margin_x && pixel.y <= float(p_camera.height) + margin_y) {
			const int u = int(std::lround(pixel.x)), v = int(std::lround(pixel.y));
			if (u >= 0 && v >= 0 && u < p_camera.width && v < p_camera.height) {
				const float reading = p_depth_m.at<float>(v, u);
				if (pc.z - radius > reading + m_options.truncation_m) { // false for NaN: kept
					continue;
				}
			}
			m_slot_frame[s] = m_frame;
		}
	}
}

IntegrationStats TsdfVolume::integrate(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera) {
	CV_Assert(p_depth_m.type() == CV_32FC1 && p_rgb.type() == CV_8UC3 && p_depth_m.size() == p_rgb.size());
	CV_Assert(p_depth_m.cols == p_camera.width && p_depth_m.rows == p_camera.height);
	IntegrationStats stats;
	m_frame++;
	// The usable readings, NaN elsewhere: the per-pixel and per-voxel loops test one NaN.
	const cv::Mat depth = clean_depth(p_depth_m, m_options.min_depth_m, m_options.max_depth_m);

	// 1. Blocks along the readings' bands: stamp those allocated, reserve the rest.
	std::vector<glm::ivec3> band;
	collect_band_blocks(depth, p_camera, p_world_from_camera, &band, &stats.valid_pixels);
	std::vector<glm::ivec3> wanted;
	for (const glm::ivec3 &block : band) {
		int32_t *slot = hash_lookup(block);
		if (slot == nullptr) {
			if (hash_insert(block, TSDF_HASH_PENDING)) {
				wanted.push_back(block);
			} else {
				stats.dropped_blocks++;
			}
		} else if (*slot >= 0) {
			m_slot_frame[size_t(*slot)] = m_frame;
			m_slot_surface[size_t(*slot)].add(m_frame);
		}
	}
	// 2. Allocated blocks in view: updated, and spared by eviction.
	mark_blocks_in_view(p_depth_m, p_camera, p_world_from_camera);

	// 3. Room for the new blocks: evict outside the view, else drop the farthest new ones.
	const int over = m_allocated + int(wanted.size()) - m_options.max_blocks;
	if (over > 0) {
		stats.evicted_blocks = evict_for(over, p_world_from_camera);
	}
	const int room = m_options.max_blocks - m_allocated;
	if (int(wanted.size()) > room) {
		std::vector<std::pair<float, glm::ivec3>> by_distance;
		for (const glm::ivec3 &b : wanted) {
			by_distance.emplace_back(keep_distance2(b, p_world_from_camera), b);
		}
		std::stable_sort(by_distance.begin(), by_distance.end(), [](const auto &p_a, const auto &p_b) { return p_a.first < p_b.first; });
		wanted.clear();
		for (size_t i = 0; i < by_distance.size(); i++) {
			if (int(i) < room) {
				wanted.push_back(by_distance[i].second);
			} else {
				hash_erase(by_distance[i].second);
				stats.dropped_blocks++;
			}
		}
	}
	for (const glm::ivec3 &block : wanted) {
		*hash_lookup(block) = allocate_slot(block);
	}
	stats.allocated_blocks = int(wanted.size());
	m_dropped_total += stats.dropped_blocks;

	// 4. Update every voxel of the blocks in view.
	update_in_view(depth, p_rgb, p_camera, p_world_from_camera, &stats);
	m_hash_version++; // blocks were allocated, evicted or reserved and dropped
	update_bounds();
	return stats;
}

void TsdfVolume::update_in_view(const cv::Mat &p_depth, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera,
		IntegrationStats *r_stats) {
	std::vector<int32_t> visible;
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s] && m_slot_frame[s] == m_frame) {
			visible.push_back(int32_t(s));
		}
	}
	r_stats->visible_blocks = int(visible.size());
	cv::Mat slope;
	TsdfFrameView frame = integration_frame(p_depth, p_rgb, p_camera, p_world_from_camera, m_options);
	const float vs = m_options.voxel_size_m;
	const glm::vec3 step_x = frame.camera_from_world_rotation[0] * vs; // glm: [i] is column i
	const glm::vec3 step_y = frame.camera_from_world_rotation[1] * vs;
	const glm::vec3 step_z = frame.camera_from_world_rotation[2] * vs;
	const DepthTiles tiles = depth_tiles(p_depth, m_options.min_depth_m, m_options.max_depth_m);
	const uint16_t full_weight = uint16_t(m_options.max_weight * TSDF_WEIGHT_UNIT);
	// Eight voxels of a row at a time where the CPU has AVX2 (the same voxels come out).
	const bool simd = m_options.simd && tsdf_simd_available();
	std::vector<uint8_t> changed(visible.size(), 0), updated(visible.size(), 0);
	// The voxels in the camera's frame, stepped by the rotated grid axes (a voxel's point is its
	// block's origin plus x, y, z steps: adds instead of a matrix product each).
	auto block_origin = [&](int32_t p_slot) {
		const glm::ivec3 base = m_slot_block[size_t(p_slot)] * TSDF_BLOCK_SIDE;
		return frame.camera_from_world_rotation * (glm::vec3(base) * vs) + frame.camera_from_world_translation;
	};
	auto may_change = [&](int32_t p_slot, const glm::vec3 &p_origin) {
		return !m_options.skip_unchanged || block_may_change(frame, tiles, p_origin, step_x, step_y, step_z, m_slot_saturated[size_t(p_slot)] != 0);
	};
	bool on_device = false;
	if (m_gpu) {
		std::vector<glm::vec3> origins(visible.size());
		parallel_for(cv::Range(0, int(visible.size())), [&](const cv::Range &p_range) {
			for (int i = p_range.start; i < p_range.end; i++) {
				origins[size_t(i)] = block_origin(visible[size_t(i)]);
				updated[size_t(i)] = may_change(visible[size_t(i)], origins[size_t(i)]) ? 1 : 0;
			}
		});
		on_device = update_on_device(frame, step_x, step_y, step_z, visible, origins, &updated, &changed);
	}
	if (!on_device) {
		add_slope_factors(p_depth, m_options, &frame, &slope);
		parallel_for(cv::Range(0, int(visible.size())), [&](const cv::Range &p_range) {
			for (int i = p_range.start; i < p_range.end; i++) {
				const int32_t slot = visible[size_t(i)];
				const glm::vec3 origin = block_origin(slot);
				// Blocks none of whose voxels could change are culled from the bounds of the
				// readings under them: most blocks in view lie wholly behind the nearer surfaces
				// or in saturated free space.
				if (!may_change(slot, origin)) {
					updated[size_t(i)] = 0;
					continue;
				}
				updated[size_t(i)] = 1;
				bool saturated = true;
				changed[size_t(i)] = update_block_voxels(frame, origin, step_x, step_y, step_z, simd, full_weight, &m_voxels[size_t(slot) * TSDF_BLOCK_VOXELS], &saturated);
				m_slot_saturated[size_t(slot)] = saturated;
			}
		});
	}
	for (size_t i = 0; i < visible.size(); i++) {
		r_stats->updated_blocks += updated[i];
		if (changed[i]) {
			m_dirty.push_back(m_slot_block[size_t(visible[i])]);
		}
	}
}

bool TsdfVolume::update_on_device(const TsdfFrameView &p_frame, const glm::vec3 &p_step_x, const glm::vec3 &p_step_y, const glm::vec3 &p_step_z,
		const std::vector<int32_t> &p_visible, const std::vector<glm::vec3> &p_origins, std::vector<uint8_t> *r_updated, std::vector<uint8_t> *r_changed) {
	std::vector<TsdfGpuBlock> list;
	std::vector<size_t> listed; // the index in p_visible of each entry
	for (size_t i = 0; i < p_visible.size(); i++) {
		if ((*r_updated)[i]) {
			const glm::vec3 &o = p_origins[i];
			list.push_back({ uint32_t(p_visible[i]), o.x, o.y, o.z });
			listed.push_back(i);
		}
	}
	std::vector<uint32_t> flags;
	std::string error;
	if (!m_gpu->integrate(p_frame, m_options.slope_smoothing_px, p_step_x, p_step_y, p_step_z, list, &flags, &error)) {
		// The CPU takes over from this frame on. A batch that failed after it started may have
		// fused part of the frame into the pool; the CPU fuses all of it again (a frame's weight
		// twice in those voxels, once).
		set_status(false, false, "integration on the GPU failed: " + error, "the pool left the device with integration");
		leave_device();
		return false;
	}
	for (size_t k = 0; k < listed.size(); k++) {
		(*r_changed)[listed[k]] = (flags[k] & TsdfIntegratorGpu::CHANGED) ? 1 : 0;
		m_slot_saturated[size_t(p_visible[listed[k]])] = (flags[k] & TsdfIntegratorGpu::SATURATED) ? 1 : 0;
	}
	return true;
}

void TsdfVolume::update_bounds() {
	glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s]) {
			lo = glm::min(lo, m_slot_block[s]);
			hi = glm::max(hi, m_slot_block[s]);
		}
	}
	if (m_allocated == 0) {
		m_bounds_min = m_bounds_max = glm::vec3(0.0f);
		return;
	}
	// A block's voxels span [8 b, 8 b + 7] voxels; the cells of trilinear reads reach 8 b + 8.
	const float block_m = float(TSDF_BLOCK_SIDE) * m_options.voxel_size_m;
	m_bounds_min = glm::vec3(lo) * block_m;
	m_bounds_max = glm::vec3(hi + glm::ivec3(1)) * block_m;
}

} // namespace roomprobe
