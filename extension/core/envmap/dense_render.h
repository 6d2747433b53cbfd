#pragma once
// The dense part of an environment map (paper §4.7, second pass): the dense model (the colour
// TSDF of slam/tsdf_volume.h) raycast from the probe into each cubemap face and painted over the
// coarse model's render, with no depth test between the two: near the probe the dense surfaces
// are the truth, and the coarse prism behind them must not show through. One exception, where the
// dense surface is the prism itself and the fisheye saw it (coarse_observed below).
//
// Each face is a 90-degree pinhole camera (fx = N / 2) at the probe, so the TSDF's own raycast
// (with its empty-space skipping) does the work. A cubemap face's (u right, v down, forward) axes
// are left-handed, so the camera is the face mirrored left to right: its pixel (x, y) is the
// face's (N - 1 - x, y). Colours: the TSDF stores the RGB camera's 8-bit
// values; p_options.lut maps them to the radiance units of the coarse texture (for the synthetic
// rig, sRGB decoding over the RGB camera's exposure; identity / 255 when absent), then the
// coarse model's lighting change since is applied (§4.6).

#include "cubemap.h"

#include <coarse/lighting.h>
#include <slam/tsdf_volume.h>

#include <array>
#include <cmath>
#include <atomic>
#include <mutex>

namespace roomprobe {

struct DenseRenderOptions {
	float near_m = 0.02f; // rays start this far from the probe, metres
	float far_m = 4.0f; // and end this far, metres
	// Raycast at 1 / scale of the face size and upsample (nearest, with the coarse render kept
	// where the low-resolution texel missed): fewer rays, blockier dense edges. Measured on the
	// demo's final model (./roomprobe bench slam): a 128² map took 26.8 ms at scale 1, 8.9 at 2,
	// 3.3 at 4, covering the same 54 % of the texels. 1: full size.
	int scale = 2;
	const std::array<float, 256> *lut = nullptr; // 8-bit value -> radiance; null: value / 255
	// The lighting change applied after the lut (a gain field at each surface point, issue #42);
	// the default is the identity.
	LightingChange lighting;
	// The room's shell first (issue #16's error budget): where the coarse render's texel was
	// observed by the fisheye (these faces >= 0.5, CV_32FC1: CoarseSnapshot::observed rendered
	// like the atlas, CoarseCubemapRenderer::render_channel) and the dense surface lies on the coarse prism (its distance within
	// shell_tolerance_m + shell_tolerance_relative x the prism's, io_cubemap's distance_m), the
	// coarse model's texel stays. On the living room's 10-s sweep the dense model showed those
	// directions at 14.9 dB and the coarse model the rest of the shell at 22.1 dB: its colours of
	// walls and floor are fused from 8-bit RGB over a few frames and keep older light. Null: the
	// paper's dense-over-all.
	const std::array<cv::Mat, 6> *coarse_observed = nullptr;
	float shell_tolerance_m = 0.05f;
	float shell_tolerance_relative = 0.02f;
	// With a DenseFaceCache: faces raycast per render (1..6, round robin); the others are the
	// cache's, of an older model (at most ceil(6 / faces_per_render) - 1 renders old). 6: all.
	int faces_per_render = 6;
};

// Whether a dense surface p_distance_m from the probe is the coarse prism p_prism_m away along the
// same direction, within DenseRenderOptions' shell tolerance.
inline bool on_coarse_shell(float p_distance_m, float p_prism_m, const DenseRenderOptions &p_options) {
	return p_prism_m > 0.0f && std::abs(p_distance_m - p_prism_m) <= p_options.shell_tolerance_m + p_options.shell_tolerance_relative * p_prism_m;
}

// One probe's low-resolution dense faces, kept between its maps (render_dense_over). Reused only
// while the position, size and scale stay the same. Its own lock: one render at a time uses it.
struct DenseFaceCache {
	std::mutex mutex;
	glm::dvec3 position = glm::dvec3(0.0);
	int size = 0, scale = 0;
	std::array<cv::Mat, 6> depth, colors; // the raycast's maps of each face (empty: never raycast)
	int next_face = 0;
	// Set by anyone (no lock needed): the next render raycasts all six faces (a final map).
	std::atomic<bool> refresh_all{ false };
};

struct DenseRenderStats {
	int texels_covered = 0; // cubemap texels the dense model now paints (full size)
	double milliseconds = 0.0;
};

// The pose of face p_face (0..5, +X -X +Y -Y +Z -Z) as a camera at p_position (x = -u, y down = +v,
// z forward = the face's axis: the face mirrored, see above): world_from_camera.
Pose cubemap_face_pose(int p_face, const glm::dvec3 &p_position);

// Which part of the coarse model's lighting changes (§4.6) the dense colours have not seen: the
// colours are as fresh as the last fused RGB-D frame, so only the changes since apply to them (a
// global approximation: blocks the RGB-D camera has not seen for a while are older still).
class DenseLighting {
public:
	// p_fused_frames: the dense model's fused frame count; p_cumulative: the coarse model's
	// cumulative change now (CoarsePipeline::cumulative_lighting). Returns the change to apply.
	LightingChange update(size_t p_fused_frames, const LightingChange &p_cumulative);
	// update(), then render_dense_over with that change as p_options' gain and offset.
	DenseRenderStats render_over(const TsdfVolume &p_volume, size_t p_fused_frames, const LightingChange &p_cumulative,
			const glm::dvec3 &p_position, DenseRenderOptions p_options, Cubemap *io_cubemap, DenseFaceCache *io_cache = nullptr);
	// Forgets the refresh (a new dense model).
	void reset();

private:
	// update() may be called by several renderers at once (the live engine's probe worker and a
	// synchronous render); the render itself needs no lock.
	std::mutex mutex;
	size_t fused_seen = 0;
	LightingChange at_refresh; // identity
};

// Paints the dense model seen from p_position over io_cubemap (any size; faces CV_32FC3). With
// io_cache, only p_options.faces_per_render faces are raycast now (see DenseFaceCache).
DenseRenderStats render_dense_over(const TsdfVolume &p_volume, const glm::dvec3 &p_position, const DenseRenderOptions &p_options, Cubemap *io_cubemap,
		DenseFaceCache *io_cache = nullptr);

} // namespace roomprobe
