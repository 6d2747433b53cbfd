#include "dense_render.h"

#include <recording/cubemap_layout.h>

#include <glm/mat3x3.hpp>

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

LightingChange DenseLighting::update(size_t p_fused_frames, const LightingChange &p_cumulative) {
	const std::lock_guard<std::mutex> lock(mutex);
	if (p_fused_frames != fused_seen) {
		fused_seen = p_fused_frames;
		at_refresh = p_cumulative;
	}
	return lighting_since(p_cumulative, at_refresh);
}

void DenseLighting::reset() {
	const std::lock_guard<std::mutex> lock(mutex);
	fused_seen = 0;
	at_refresh = LightingChange();
}

DenseRenderStats DenseLighting::render_over(const TsdfVolume &p_volume, size_t p_fused_frames, const LightingChange &p_cumulative,
		const glm::dvec3 &p_position, DenseRenderOptions p_options, Cubemap *io_cubemap) {
	const LightingChange change = update(p_fused_frames, p_cumulative);
	p_options.gain = change.gain;
	p_options.offset = change.offset;
	return render_dense_over(p_volume, p_position, p_options, io_cubemap);
}

DenseRenderStats render_dense_over(const TsdfVolume &p_volume, const glm::dvec3 &p_position, const DenseRenderOptions &p_options, Cubemap *io_cubemap) {
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
	for (int f = 0; f < 6; f++) {
		ModelMaps maps;
		p_volume.raycast(face_camera, cubemap_face_pose(f, p_position), p_options.near_m, p_options.far_m, &maps, nullptr, false);
		cv::Mat &face = io_cubemap->faces[size_t(f)];
		for (int v = 0; v < size; v++) {
			const int lv = std::min(low - 1, v * low / size);
			const float *depth = maps.depth.ptr<float>(lv);
			const cv::Vec3b *color = maps.colors.ptr<cv::Vec3b>(lv);
			cv::Vec3f *out = face.ptr<cv::Vec3f>(v);
			for (int u = 0; u < size; u++) {
				const int lu = low - 1 - std::min(low - 1, u * low / size); // mirrored
				const cv::Vec3b c = color[lu];
				// No surface, or a surface whose colour was never observed (fused from depth at the
				// edge of the colour band only): the coarse model shows here.
				if (!std::isfinite(depth[lu]) || (c[0] == 0 && c[1] == 0 && c[2] == 0)) {
					continue;
				}
				for (int k = 0; k < 3; k++) {
					out[u][k] = std::max(0.0f, p_options.gain[k] * lut[c[k]] + p_options.offset[k]);
				}
				stats.texels_covered++;
			}
		}
	}
	stats.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	return stats;
}

} // namespace roomprobe
