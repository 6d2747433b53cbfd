#include "dense_render.h"

#include <types/cubemap_layout.h>

#include <glm/mat3x3.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace roomprobe {

Pose cubemap_face_pose(int p_face, const glm::dvec3 &p_position) {
	// On a 2 x 2 face, (0.5, 0.5) is the centre, (1.5, 0.5) looks along forward + right and
	// (0.5, 1.5) along forward + down, both normalised: the face's axes, from the one convention.
	const glm::dvec3 forward = cubemap_direction(p_face, 0.5, 0.5, 2);
	const glm::dvec3 right = glm::normalize(cubemap_direction(p_face, 1.5, 0.5, 2) * std::sqrt(2.0) - forward);
	const glm::dvec3 down = glm::normalize(cubemap_direction(p_face, 0.5, 1.5, 2) * std::sqrt(2.0) - forward);
	const glm::dmat3 rotation(-right, down, forward); // columns: the camera's axes (right-handed)
	Pose pose;
	pose.rotation = glm::quat_cast(rotation);
	pose.translation = p_position;
	return pose;
}

DenseLightingEpochs DenseLightingEpochs::uniform(const LightingChange &p_change) {
	DenseLightingEpochs epochs;
	epochs.first_frame.push_back(0);
	epochs.since.push_back(p_change);
	return epochs;
}

int DenseLightingEpochs::epoch_of(uint32_t p_frame) const {
	if (p_frame == 0) {
		return int(since.size()) - 1;
	}
	const auto after = std::upper_bound(first_frame.begin(), first_frame.end(), p_frame);
	return after == first_frame.begin() ? 0 : int(after - first_frame.begin()) - 1;
}

const LightingChange &DenseLightingEpochs::at_frame(uint32_t p_frame) const {
	return since[size_t(epoch_of(p_frame))];
}

DenseLightingEpochs::Mix DenseLightingEpochs::mix(const TsdfSurfaceFrames &p_frames, int p_max_color_weight) const {
	Mix out;
	const int kept = p_frames.kept();
	if (kept == 0) {
		out.count = 1;
		out.epoch[0] = epoch_of(0); // no block: the newest
		out.share[0] = 1.0;
		return out;
	}
	// The frames are newest first, so their epochs only go down: one search, then a walk.
	int epoch = epoch_of(p_frames.frames[0]);
	const uint32_t cap = uint32_t(std::max(1, p_max_color_weight));
	double remaining = 1.0;
	for (int j = 0; j < kept; j++) {
		while (epoch > 0 && first_frame[size_t(epoch)] > p_frames.frames[j]) {
			epoch--; // what epoch_of(frames[j]) gives
		}
		// This frame's share of the running mean (the TSDF's colour update); the oldest kept
		// takes what is left.
		const uint32_t observation = p_frames.count - uint32_t(j); // 1-based
		const double share = j + 1 == kept ? 1.0 : 1.0 / double(std::min(observation - 1, cap) + 1);
		const double weight = remaining * share;
		remaining -= weight;
		if (out.count > 0 && out.epoch[out.count - 1] == epoch) {
			out.share[out.count - 1] += weight;
		} else {
			out.epoch[out.count] = epoch;
			out.share[out.count] = weight;
			out.count++;
		}
	}
	return out;
}

LightingChange DenseLightingEpochs::for_mix(const Mix &p_mix, const glm::vec3 &p_point) const {
	const LightingChange &newest = since[size_t(p_mix.epoch[0])];
	LightingChange out = newest;
	out.log_slope = cv::Vec3f(0.0f, 0.0f, 0.0f);
	if (p_mix.count == 1) {
		out.gain = newest.has_field() ? newest.gain_at(p_point) : newest.gain;
		return out;
	}
	cv::Vec3d a(0.0, 0.0, 0.0), b(0.0, 0.0, 0.0); // the mean = now * a - b, per channel
	for (int k = 0; k < p_mix.count; k++) {
		const LightingChange &change = since[size_t(p_mix.epoch[k])];
		const cv::Vec3f gain = change.has_field() ? change.gain_at(p_point) : change.gain;
		for (int c = 0; c < 3; c++) {
			// A gain of 0 cannot be undone: those colours count as of the lighting now.
			const double g = gain[c] > 0.0f ? double(gain[c]) : 1.0;
			const double o = gain[c] > 0.0f ? double(change.offset[c]) : 0.0;
			a[c] += p_mix.share[k] / g;
			b[c] += p_mix.share[k] * o / g;
		}
	}
	for (int c = 0; c < 3; c++) {
		out.gain[c] = float(1.0 / a[c]);
		out.offset[c] = float(b[c] / a[c]);
	}
	return out;
}

LightingChange DenseLightingEpochs::for_block(const TsdfSurfaceFrames &p_frames, const glm::vec3 &p_point, int p_max_color_weight) const {
	return for_mix(mix(p_frames, p_max_color_weight), p_point);
}

bool DenseLightingEpochs::has_field() const {
	for (const LightingChange &change : since) {
		if (change.has_field()) {
			return true;
		}
	}
	return false;
}

bool DenseLightingEpochs::per_point() const {
	for (const LightingChange &change : since) {
		if (change.has_field() || change.gain != since[0].gain || change.offset != since[0].offset) {
			return true;
		}
	}
	return false;
}

namespace {

// Whether two cumulative changes are the same to within rounding (DenseLighting's thresholds).
bool same_lighting(const LightingChange &p_a, const LightingChange &p_b) {
	const LightingChange d = lighting_since(p_a, p_b);
	for (int c = 0; c < 3; c++) {
		if (std::abs(d.gain[c] - 1.0f) > 0.005f || std::abs(d.offset[c]) > 0.001f || std::abs(d.log_slope[c]) > 0.005f) {
			return false;
		}
	}
	return true;
}

} // namespace

void DenseLighting::record(uint32_t p_volume_frame, const LightingChange &p_cumulative) {
	const std::lock_guard<std::mutex> lock(mutex);
	if (!first_frame.empty() && same_lighting(p_cumulative, cumulative.back())) {
		return;
	}
	if (!first_frame.empty() && p_volume_frame <= first_frame.back()) {
		cumulative.back() = p_cumulative; // the same frames, recorded again
		return;
	}
	first_frame.push_back(p_volume_frame);
	cumulative.push_back(p_cumulative);
	if (first_frame.size() > MAX_EPOCHS) {
		first_frame.erase(first_frame.begin()); // its colours now count as the next epoch's
		cumulative.erase(cumulative.begin());
	}
}

DenseLightingEpochs DenseLighting::epochs(const LightingChange &p_cumulative) const {
	const std::lock_guard<std::mutex> lock(mutex);
	if (first_frame.empty()) {
		return DenseLightingEpochs::uniform(LightingChange());
	}
	DenseLightingEpochs out;
	out.first_frame = first_frame;
	out.since.reserve(cumulative.size());
	for (const LightingChange &then : cumulative) {
		out.since.push_back(lighting_since(p_cumulative, then));
	}
	return out;
}

void DenseLighting::reset() {
	const std::lock_guard<std::mutex> lock(mutex);
	first_frame.clear();
	cumulative.clear();
}

DenseRenderStats DenseLighting::render_over(const TsdfVolume &p_volume, const LightingChange &p_cumulative, const glm::dvec3 &p_position,
		DenseRenderOptions p_options, Cubemap *io_cubemap, DenseFaceCache *io_cache) const {
	p_options.lighting = epochs(p_cumulative);
	return render_dense_over(p_volume, p_position, p_options, io_cubemap, io_cache);
}

DenseRenderStats render_dense_over(const TsdfVolume &p_volume, const glm::dvec3 &p_position, const DenseRenderOptions &p_options, Cubemap *io_cubemap,
		DenseFaceCache *io_cache) {
	const auto start = std::chrono::steady_clock::now();
	DenseRenderStats stats;
	if (io_cubemap == nullptr || !is_valid_cubemap(*io_cubemap) || p_volume.stats().allocated_blocks == 0) {
		return stats;
	}
	const int size = io_cubemap->size;
	const int scale = std::max(1, p_options.scale);
	const int low = std::max(1, size / scale);
	PinholeIntrinsics face_camera;
	face_camera.width = face_camera.height = low;
	face_camera.fx = face_camera.fy = 0.5f * float(low);
	face_camera.cx = face_camera.cy = 0.5f * float(low - 1);
	std::array<float, 256> identity;
	for (int i = 0; i < 256; i++) {
		identity[size_t(i)] = float(i) / 255.0f;
	}
	const std::array<float, 256> &lut = p_options.lut != nullptr ? *p_options.lut : identity;
	const bool has_distances = roomprobe::has_distances(*io_cubemap);
	// The texel's surface point is needed where the change depends on it (a field, or epochs).
	const DenseLightingEpochs uniform = p_options.lighting.empty() ? DenseLightingEpochs::uniform(LightingChange()) : DenseLightingEpochs();
	const DenseLightingEpochs &lighting = p_options.lighting.empty() ? uniform : p_options.lighting;
	const bool per_point = lighting.per_point();
	const bool field = lighting.has_field();
	struct {
		bool valid = false;
		glm::ivec3 block = glm::ivec3(0);
		DenseLightingEpochs::Mix mix;
		LightingChange change;
	} memo; // the last block a texel's surface lay in
	const std::array<cv::Mat, 6> *observed_faces = has_distances && p_options.coarse_observed != nullptr &&
					(*p_options.coarse_observed)[0].rows == size && (*p_options.coarse_observed)[0].type() == CV_32FC1
			? p_options.coarse_observed
			: nullptr;
	// Which faces are raycast now: all without a cache (or after a move); else the next ones.
	std::unique_lock<std::mutex> cache_lock;
	std::array<bool, 6> raycast_now;
	raycast_now.fill(true);
	if (io_cache != nullptr) {
		cache_lock = std::unique_lock<std::mutex>(io_cache->mutex);
		if (io_cache->position != p_position || io_cache->size != size || io_cache->scale != scale) {
			io_cache->depth = {};
			io_cache->colors = {};
			io_cache->next_face = 0;
			io_cache->position = p_position;
			io_cache->size = size;
			io_cache->scale = scale;
		}
		const int per_render = std::clamp(p_options.faces_per_render, 1, 6);
		raycast_now.fill(false);
		for (int i = 0; i < per_render; i++) {
			raycast_now[size_t((io_cache->next_face + i) % 6)] = true;
		}
		io_cache->next_face = (io_cache->next_face + per_render) % 6;
		const bool all = io_cache->refresh_all.exchange(false);
		for (int f = 0; f < 6; f++) {
			raycast_now[size_t(f)] = all || raycast_now[size_t(f)] || io_cache->depth[size_t(f)].empty();
		}
	}
	for (int f = 0; f < 6; f++) {
		ModelMaps maps;
		if (raycast_now[size_t(f)]) {
			p_volume.raycast(face_camera, cubemap_face_pose(f, p_position), p_options.near_m, p_options.far_m, &maps, nullptr, false);
			if (io_cache != nullptr) {
				io_cache->depth[size_t(f)] = maps.depth;
				io_cache->colors[size_t(f)] = maps.colors;
			}
		} else {
			maps.depth = io_cache->depth[size_t(f)];
			maps.colors = io_cache->colors[size_t(f)];
		}
		cv::Mat &face = io_cubemap->faces[size_t(f)];
		// The map's distances where it has them: depth (z along the face's axis) over the cosine
		// of the texel's own direction to the axis (the prism's distance is the texel centre's).
		float *distances = has_distances ? io_cubemap->distance_m[size_t(f)].ptr<float>() : nullptr;
		for (int v = 0; v < size; v++) {
			const int lv = std::min(low - 1, v * low / size);
			const float *depth = maps.depth.ptr<float>(lv);
			const cv::Vec3b *color = maps.colors.ptr<cv::Vec3b>(lv);
			cv::Vec3f *out = face.ptr<cv::Vec3f>(v);
			const float *observed = observed_faces != nullptr ? (*observed_faces)[size_t(f)].ptr<float>(v) : nullptr;
			const float dy = (float(v) - 0.5f * float(size - 1)) / (0.5f * float(size));
			for (int u = 0; u < size; u++) {
				const int lu = low - 1 - std::min(low - 1, u * low / size); // mirrored
				const cv::Vec3b c = color[lu];
				// No surface, or a surface whose colour was never observed (fused from depth at the
				// edge of the colour band only): the coarse model shows here.
				if (!std::isfinite(depth[lu]) || (c[0] == 0 && c[1] == 0 && c[2] == 0)) {
					continue;
				}
				// The surface's distance from the probe: depth over the cosine to the face's axis.
				const float dx = (float(u) - 0.5f * float(size - 1)) / (0.5f * float(size)); // mirrored: the sign does not matter
				const float distance = distances != nullptr || per_point ? depth[lu] * std::sqrt(1.0f + dx * dx + dy * dy) : 0.0f;
				if (distances != nullptr) {
					float &prism = distances[size_t(v) * size_t(size) + size_t(u)];
					if (observed != nullptr && observed[u] >= 0.5f && on_coarse_shell(distance, prism, p_options)) {
						continue; // the shell the fisheye saw: the coarse model's texel stays
					}
					prism = distance;
				}
				const cv::Vec3f value(lut[c[0]], lut[c[1]], lut[c[2]]);
				if (per_point) {
					// The surface point: the texel's direction times its distance; its block's mix of
					// epochs, shared with the texels before it in the same block.
					const glm::vec3 point(p_position + cubemap_direction(f, double(u), double(v), size) * double(distance));
					const glm::ivec3 block = p_volume.block_at(point);
					if (block != memo.block || !memo.valid) {
						memo.block = block;
						memo.valid = true;
						memo.mix = lighting.mix(p_volume.surface_frames(block), p_volume.options().max_color_weight);
						if (!field) {
							memo.change = lighting.for_mix(memo.mix, point); // the same at every point of the block
						}
					}
					out[u] = (field ? lighting.for_mix(memo.mix, point) : memo.change).apply(value);
				} else {
					out[u] = lighting.since[0].apply(value);
				}
				stats.texels_covered++;
			}
		}
	}
	stats.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	return stats;
}

} // namespace roomprobe
