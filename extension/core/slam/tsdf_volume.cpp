#include "tsdf_volume.h"

#include "depth_pyramid.h"
#include "tsdf_capacity.h"
#include "tsdf_integrate_simd.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <new>
#include <stdexcept>

namespace roomprobe {

namespace {

// Rows per parallel_for_ stripe: enough work per task, and a fixed split.
constexpr int ROWS_PER_STRIPE = 8;
// The hash table is kept at most this full (linear probing degrades beyond).
constexpr double MAX_HASH_LOAD = 0.75;

glm::mat3 rotation_matrix(const Pose &p_pose) {
	return glm::mat3(glm::mat3_cast(glm::quat(p_pose.rotation)));
}

glm::vec3 block_centre(const glm::ivec3 &p_block, float p_voxel_size) {
	// Voxels 0..7 of a block sit at (8 b + i) voxels; its centre is at 8 b + 3.5.
	return (glm::vec3(p_block) * float(TSDF_BLOCK_SIDE) + glm::vec3(0.5f * float(TSDF_BLOCK_SIDE - 1))) * p_voxel_size;
}

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

constexpr int TSDF_MAX_BLOCKS = 1 << 22;

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
	cv::parallel_for_(cv::Range(0, tiles.rows), [&](const cv::Range &p_range) {
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

uint32_t hash_size_for(int p_max_blocks) {
	uint32_t size = 1024;
	while (double(size) * MAX_HASH_LOAD < 1.5 * double(p_max_blocks)) {
		size *= 2;
	}
	return size;
}

} // namespace

TsdfVolume::TsdfVolume(const TsdfOptions &p_options) :
		m_options(p_options) {
	// 1 << 22 blocks is 24 GiB of voxels: beyond any machine this runs on, and the hash table's
	// size (a power of two of 32 bits) would overflow past it.
	m_options.max_blocks = std::clamp(m_options.max_blocks, 1, TSDF_MAX_BLOCKS);
	m_options.max_weight = std::clamp(m_options.max_weight, 1, 65535 / TSDF_WEIGHT_UNIT);
	// A cap this machine cannot hold is refused, naming it and the memory it needs (issue #38: the
	// top of the range ended in a bare std::bad_alloc from the reservation below).
	const std::string too_big = tsdf_capacity_problem("max_blocks", m_options.max_blocks, physical_memory_bytes());
	if (!too_big.empty()) {
		throw std::runtime_error(too_big);
	}
	try {
		m_hash.assign(hash_size_for(m_options.max_blocks), TsdfHashEntry());
		m_hash_mask = uint32_t(m_hash.size()) - 1;
		// Address space for the whole cap at once, so that the pool never moves; pages are only
		// committed as blocks are first written.
		m_voxels.reserve(size_t(m_options.max_blocks) * TSDF_BLOCK_VOXELS);
	} catch (const std::bad_alloc &) { // an address-space limit (ulimit -v), or no overcommit
		char text[256];
		std::snprintf(text, sizeof(text), "max_blocks %d: the %.1f GiB its full model needs could not be reserved (out of memory or address space): lower max_blocks",
				m_options.max_blocks, double(tsdf_capacity_bytes(m_options.max_blocks)) / double(uint64_t(1) << 30));
		throw std::runtime_error(text);
	}
}

// ---- hash table ----

int32_t *TsdfVolume::hash_lookup(const glm::ivec3 &p_block) {
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY) {
		if (m_hash[i].block == p_block) {
			return &m_hash[i].slot;
		}
		i = (i + 1) & m_hash_mask;
	}
	return nullptr;
}

bool TsdfVolume::hash_insert(const glm::ivec3 &p_block, int32_t p_slot) {
	if (double(m_hash_used + 1) > MAX_HASH_LOAD * double(m_hash.size())) {
		return false;
	}
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY) {
		i = (i + 1) & m_hash_mask;
	}
	m_hash[i] = { p_block, p_slot };
	m_hash_used++;
	return true;
}

void TsdfVolume::hash_erase(const glm::ivec3 &p_block) {
	uint32_t i = tsdf_block_hash(p_block) & m_hash_mask;
	while (m_hash[i].slot != TSDF_HASH_EMPTY && m_hash[i].block != p_block) {
		i = (i + 1) & m_hash_mask;
	}
	if (m_hash[i].slot == TSDF_HASH_EMPTY) {
		return;
	}
	// Backward-shift deletion: move later entries of the run into the hole when their home slot
	// does not lie (cyclically) between the hole and them, so that no probe sequence breaks.
	uint32_t hole = i;
	uint32_t j = i;
	for (;;) {
		j = (j + 1) & m_hash_mask;
		if (m_hash[j].slot == TSDF_HASH_EMPTY) {
			break;
		}
		const uint32_t home = tsdf_block_hash(m_hash[j].block) & m_hash_mask;
		const bool home_in_range = hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
		if (!home_in_range) {
			m_hash[hole] = m_hash[j];
			hole = j;
		}
	}
	m_hash[hole] = TsdfHashEntry();
	m_hash_used--;
}

// ---- pool ----

int32_t TsdfVolume::allocate_slot(const glm::ivec3 &p_block) {
	int32_t slot;
	if (!m_free_slots.empty()) {
		slot = m_free_slots.back();
		m_free_slots.pop_back();
		std::fill_n(m_voxels.begin() + ptrdiff_t(slot) * TSDF_BLOCK_VOXELS, TSDF_BLOCK_VOXELS, TsdfVoxel());
	} else {
		slot = int32_t(m_slot_block.size());
		m_slot_block.push_back(p_block);
		m_slot_used.push_back(0);
		m_slot_frame.push_back(0);
		m_slot_saturated.push_back(0);
		m_voxels.resize(m_voxels.size() + TSDF_BLOCK_VOXELS);
	}
	m_slot_block[size_t(slot)] = p_block;
	m_slot_used[size_t(slot)] = 1;
	m_slot_frame[size_t(slot)] = m_frame;
	m_slot_saturated[size_t(slot)] = 0;
	m_allocated++;
	return slot;
}

void TsdfVolume::free_slot(int32_t p_slot) {
	m_slot_used[size_t(p_slot)] = 0;
	m_free_slots.push_back(p_slot);
	m_allocated--;
}

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
	cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range &p_range) {
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

float TsdfVolume::keep_distance2(const glm::ivec3 &p_block, const Pose &p_world_from_camera) const {
	const glm::dvec3 c(block_centre(p_block, m_options.voxel_size_m));
	if (m_keep_points.empty()) {
		const glm::dvec3 d = c - p_world_from_camera.translation;
		return float(glm::dot(d, d));
	}
	double best = std::numeric_limits<double>::infinity();
	for (const glm::dvec3 &k : m_keep_points) {
		const glm::dvec3 d = c - k;
		best = std::min(best, glm::dot(d, d));
	}
	return float(best);
}

int TsdfVolume::evict_for(int p_needed, const Pose &p_world_from_camera) {
	std::vector<std::pair<float, int32_t>> candidates; // (-distance², slot): farthest first
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s] && m_slot_frame[s] != m_frame) {
			candidates.emplace_back(-keep_distance2(m_slot_block[s], p_world_from_camera), int32_t(s));
		}
	}
	const int count = std::min(p_needed, int(candidates.size()));
	std::nth_element(candidates.begin(), candidates.begin() + count, candidates.end());
	for (int i = 0; i < count; i++) {
		const int32_t slot = candidates[size_t(i)].second;
		hash_erase(m_slot_block[size_t(slot)]);
		m_dirty.push_back(m_slot_block[size_t(slot)]);
		free_slot(slot);
	}
	m_evicted_total += count;
	return count;
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
	std::vector<int32_t> visible;
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s] && m_slot_frame[s] == m_frame) {
			visible.push_back(int32_t(s));
		}
	}
	stats.visible_blocks = int(visible.size());
	const Pose camera_from_world = inverse(p_world_from_camera);
	TsdfFrameView frame;
	frame.camera = p_camera;
	frame.camera_from_world_rotation = rotation_matrix(camera_from_world);
	frame.camera_from_world_translation = glm::vec3(camera_from_world.translation);
	frame.depth = depth.ptr<float>(0);
	frame.depth_stride = depth.step1();
	frame.rgb = p_rgb.ptr<uint8_t>(0);
	frame.rgb_stride = p_rgb.step[0];
	frame.truncation_m = m_options.truncation_m;
	frame.color_band_m = m_options.color_band_m;
	frame.min_depth_m = m_options.min_depth_m;
	frame.max_depth_m = m_options.max_depth_m;
	frame.behind_limit_m = tsdf_behind_limit(m_options.truncation_m, m_options.min_slope);
	frame.max_weight = uint16_t(m_options.max_weight);
	frame.max_color_weight = uint16_t(std::clamp(m_options.max_color_weight, 1, 65535));
	// Slope factors of the frame's pixels (tsdf_depth_slope); a depth jump of half the band
	// between neighbours is an edge. Taken on the depth smoothed as ICP smooths it: a sensor's
	// noise (centimetres at 3 m) over one-pixel differences (6 mm there) would tilt the tangent
	// planes at random and reject most far readings as grazing.
	const cv::Mat smoothed = m_options.slope_smoothing_px > 0 ? smooth_depth(depth, m_options.slope_smoothing_px, m_options.truncation_m) : depth;
	cv::Mat slope(p_depth_m.size(), CV_32FC1);
	const float *smoothed_data = smoothed.ptr<float>(0);
	const size_t smoothed_stride = smoothed.step1();
	cv::parallel_for_(cv::Range(0, p_depth_m.rows), [&](const cv::Range &p_range) {
		for (int v = p_range.start; v < p_range.end; v++) {
			float *row = slope.ptr<float>(v);
			for (int u = 0; u < p_depth_m.cols; u++) {
				row[u] = tsdf_depth_slope(smoothed_data, smoothed_stride, p_camera, u, v, 0.5f * m_options.truncation_m);
			}
		}
	});
	frame.slope = slope.ptr<float>(0);
	frame.slope_stride = slope.step1();
	frame.min_slope = m_options.min_slope;
	const float vs = m_options.voxel_size_m;
	const glm::vec3 step_x = frame.camera_from_world_rotation[0] * vs; // glm: [i] is column i
	const glm::vec3 step_y = frame.camera_from_world_rotation[1] * vs;
	const glm::vec3 step_z = frame.camera_from_world_rotation[2] * vs;
	frame.early_exits = m_options.skip_unchanged;
	// Blocks none of whose voxels could change are culled from the bounds of the readings under
	// them: most blocks in view lie wholly behind the nearer surfaces or in saturated free space.
	const DepthTiles tiles = depth_tiles(depth, m_options.min_depth_m, m_options.max_depth_m);
	const uint16_t full_weight = uint16_t(m_options.max_weight * TSDF_WEIGHT_UNIT);
	// Eight voxels of a row at a time where the CPU has AVX2 (the same voxels come out).
	const bool simd = m_options.simd && tsdf_simd_available();
	std::vector<uint8_t> changed(visible.size(), 0), updated(visible.size(), 0);
	cv::parallel_for_(cv::Range(0, int(visible.size())), [&](const cv::Range &p_range) {
		for (int i = p_range.start; i < p_range.end; i++) {
			const int32_t slot = visible[size_t(i)];
			const glm::ivec3 base = m_slot_block[size_t(slot)] * TSDF_BLOCK_SIDE;
			// The voxels in the camera's frame, stepped by the rotated grid axes (a voxel's point
			// is its block's origin plus x, y, z steps: adds instead of a matrix product each).
			const glm::vec3 origin = frame.camera_from_world_rotation * (glm::vec3(base) * vs) + frame.camera_from_world_translation;
			if (m_options.skip_unchanged && !block_may_change(frame, tiles, origin, step_x, step_y, step_z, m_slot_saturated[size_t(slot)] != 0)) {
				continue;
			}
			updated[size_t(i)] = 1;
			TsdfVoxel *voxel = &m_voxels[size_t(slot) * TSDF_BLOCK_VOXELS];
			bool any = false;
			bool saturated = true;
			for (int z = 0; z < TSDF_BLOCK_SIDE; z++) {
				for (int y = 0; y < TSDF_BLOCK_SIDE; y++, voxel += TSDF_BLOCK_SIDE) {
					const glm::vec3 row = origin + float(y) * step_y + float(z) * step_z;
					if (simd) {
						any |= tsdf_update_row_simd(frame, row, step_x, voxel);
					} else {
						for (int x = 0; x < TSDF_BLOCK_SIDE; x++) {
							any |= tsdf_update_voxel_at(frame, row + float(x) * step_x, voxel + x);
						}
					}
					for (int x = 0; x < TSDF_BLOCK_SIDE && saturated; x++) { // a block near a surface stops at its first row
						saturated = voxel[x].tsdf == 1.0f && voxel[x].weight == full_weight;
					}
				}
			}
			changed[size_t(i)] = any;
			m_slot_saturated[size_t(slot)] = saturated;
		}
	});
	for (size_t i = 0; i < visible.size(); i++) {
		stats.updated_blocks += updated[i];
		if (changed[i]) {
			m_dirty.push_back(m_slot_block[size_t(visible[i])]);
		}
	}
	update_bounds();
	return stats;
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

// ---- queries ----

TsdfView TsdfVolume::view() const {
	TsdfView view;
	view.entries = m_hash.data();
	view.mask = m_hash_mask;
	view.voxels = m_voxels.data();
	view.voxel_size = m_options.voxel_size_m;
	view.truncation = m_options.truncation_m;
	return view;
}

// ---- raycast ----

namespace {

// Pixels per side of a cell of the depth-range image.
constexpr int RANGE_CELL = 8;

} // namespace

cv::Mat TsdfVolume::depth_ranges(const PinholeIntrinsics &p_camera, const Pose &p_world_from_camera, float p_near_m, float p_far_m) const {
	// Per cell of RANGE_CELL^2 pixels, the [min, max] camera depth of the allocated blocks that
	// project onto it (InfiniTAM's expected depths): rays start at the first block they can
	// meet and stop after the last, and cells no block covers are not marched at all.
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
	cv::parallel_for_(cv::Range(0, CHUNKS), [&](const cv::Range &p_range) {
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
		RaycastStats *r_stats) const {
	CV_Assert(p_search_m.type() == CV_32FC2 && p_search_m.cols == p_camera.width && p_search_m.rows == p_camera.height);
	raycast_ranged(p_camera, p_world_from_camera, m_options.min_depth_m, m_options.max_depth_m, &p_search_m, true, r_maps, r_stats);
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
	r_maps->points.setTo(cv::Scalar::all(nan));
	r_maps->normals.setTo(cv::Scalar::all(nan));
	r_maps->colors.setTo(cv::Scalar::all(0));
	r_maps->depth.setTo(cv::Scalar::all(nan));
	RaycastStats stats;
	if (m_allocated == 0) {
		if (r_stats != nullptr) {
			*r_stats = stats;
		}
		return;
	}
	const TsdfView view = this->view();
	TsdfRayParams ray;
	ray.origin = glm::vec3(p_world_from_camera.translation);
	ray.world_from_camera_rotation = rotation_matrix(p_world_from_camera);
	ray.min_depth_m = p_min_depth_m;
	ray.max_depth_m = p_max_depth_m;
	ray.bounds_min = m_bounds_min;
	ray.bounds_max = m_bounds_max;
	ray.normals = p_normals;
	const cv::Mat ranges = depth_ranges(p_camera, p_world_from_camera, p_min_depth_m, p_max_depth_m);
	std::vector<long long> steps(size_t(p_camera.height), 0);
	std::vector<int> hits(size_t(p_camera.height), 0);
	cv::parallel_for_(cv::Range(0, p_camera.height), [&](const cv::Range &p_range) {
		for (int v = p_range.start; v < p_range.end; v++) {
			cv::Vec3f *points = r_maps->points.ptr<cv::Vec3f>(v);
			cv::Vec3f *normals = r_maps->normals.ptr<cv::Vec3f>(v);
			cv::Vec3b *colors = r_maps->colors.ptr<cv::Vec3b>(v);
			float *depth = r_maps->depth.ptr<float>(v);
			const cv::Vec2f *range_row = ranges.ptr<cv::Vec2f>(v / RANGE_CELL);
			const cv::Vec2f *search_row = p_search_m != nullptr ? p_search_m->ptr<cv::Vec2f>(v) : nullptr;
			for (int u = 0; u < p_camera.width; u++) {
				cv::Vec2f range = range_row[u / RANGE_CELL];
				if (search_row != nullptr && std::isfinite(search_row[u][0]) && std::isfinite(search_row[u][1])) {
					range = cv::Vec2f(std::max(range[0], search_row[u][0]), std::min(range[1], search_row[u][1]));
				}
				if (!(range[0] <= range[1])) {
					continue; // no block projects here
				}
				TsdfRayParams pixel_ray = ray;
				pixel_ray.min_depth_m = std::max(ray.min_depth_m, range[0]);
				pixel_ray.max_depth_m = std::min(ray.max_depth_m, range[1]);
				TsdfRayHit hit;
				int n = 0;
				const bool ok = tsdf_raycast_pixel(view, pixel_ray, p_camera, u, v, &hit, &n);
				steps[size_t(v)] += n;
				if (!ok) {
					continue;
				}
				hits[size_t(v)]++;
				points[u] = cv::Vec3f(hit.point.x, hit.point.y, hit.point.z);
				normals[u] = cv::Vec3f(hit.normal.x, hit.normal.y, hit.normal.z);
				colors[u] = cv::Vec3b(cv::saturate_cast<uint8_t>(hit.rgb.x), cv::saturate_cast<uint8_t>(hit.rgb.y), cv::saturate_cast<uint8_t>(hit.rgb.z));
				depth[u] = hit.depth;
			}
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

const TsdfVoxel *TsdfVolume::find_block(const glm::ivec3 &p_block) const {
	const int32_t slot = tsdf_find_slot(view(), p_block);
	return slot >= 0 ? &m_voxels[size_t(slot) * TSDF_BLOCK_VOXELS] : nullptr;
}

namespace {
bool ivec3_less(const glm::ivec3 &p_a, const glm::ivec3 &p_b) {
	if (p_a.x != p_b.x) {
		return p_a.x < p_b.x;
	}
	if (p_a.y != p_b.y) {
		return p_a.y < p_b.y;
	}
	return p_a.z < p_b.z;
}
} // namespace

std::vector<glm::ivec3> TsdfVolume::allocated_blocks() const {
	std::vector<glm::ivec3> blocks;
	for (size_t s = 0; s < m_slot_block.size(); s++) {
		if (m_slot_used[s]) {
			blocks.push_back(m_slot_block[s]);
		}
	}
	std::sort(blocks.begin(), blocks.end(), ivec3_less);
	return blocks;
}

std::vector<glm::ivec3> TsdfVolume::take_dirty_blocks() {
	std::vector<glm::ivec3> dirty;
	dirty.swap(m_dirty);
	std::sort(dirty.begin(), dirty.end(), ivec3_less);
	dirty.erase(std::unique(dirty.begin(), dirty.end()), dirty.end());
	return dirty;
}

void TsdfVolume::set_keep_points(const std::vector<glm::dvec3> &p_points) {
	m_keep_points = p_points;
}

void TsdfVolume::reset() {
	for (const glm::ivec3 &block : allocated_blocks()) {
		m_dirty.push_back(block);
	}
	std::fill(m_hash.begin(), m_hash.end(), TsdfHashEntry());
	m_hash_used = 0;
	m_voxels.clear();
	m_slot_block.clear();
	m_slot_used.clear();
	m_slot_frame.clear();
	m_slot_saturated.clear();
	m_free_slots.clear();
	m_allocated = 0;
	m_bounds_min = m_bounds_max = glm::vec3(0.0f);
}

TsdfStats TsdfVolume::stats() const {
	TsdfStats stats;
	stats.allocated_blocks = m_allocated;
	stats.capacity_blocks = m_options.max_blocks;
	const size_t block_bytes = sizeof(TsdfVoxel) * TSDF_BLOCK_VOXELS + sizeof(glm::ivec3) + 2 * sizeof(uint32_t);
	const size_t hash_bytes = m_hash.size() * sizeof(TsdfHashEntry);
	stats.bytes_used = size_t(m_allocated) * block_bytes + hash_bytes;
	stats.bytes_reserved = m_slot_block.size() * block_bytes + hash_bytes;
	stats.evicted_blocks_total = m_evicted_total;
	stats.dropped_blocks_total = m_dropped_total;
	stats.bounds_min = m_bounds_min;
	stats.bounds_max = m_bounds_max;
	return stats;
}

} // namespace roomprobe
