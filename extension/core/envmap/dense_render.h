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
#include <vector>

namespace roomprobe {

// The lighting change (§4.6) each dense colour has not seen yet. A block's colours are of the
// lighting of the frames a reading's surface crossed it (TsdfVolume::surface_frames): epoch k
// holds the colours fused from volume frame first_frame[k] until the next epoch's, and since[k]
// takes them to the lighting now. A block the camera left before the light switched on keeps
// its old colours until seen again, and still shows the new light; one seen across the switch
// holds a mean of both, which for_block undoes.
struct DenseLightingEpochs {
	std::vector<uint32_t> first_frame; // ascending; empty: the identity everywhere
	std::vector<LightingChange> since;

	// One change for every colour (tests; a model with no history).
	static DenseLightingEpochs uniform(const LightingChange &p_change);
	// The change for colours fused at volume frame p_frame: the epoch holding it, the first one
	// before any. 0 (a block not found) takes the newest: the old single-change rule.
	const LightingChange &at_frame(uint32_t p_frame) const;
	int epoch_of(uint32_t p_frame) const; // at_frame's index into since
	bool empty() const { return since.empty(); }
	// The change for the colours of a block whose surface was fused at p_frames
	// (TsdfVolume::surface_frames), at its point p_point: each frame's colour was of its epoch's
	// lighting, and the voxel keeps their running mean (equal shares up to p_max_color_weight
	// observations, then 1 / (p_max_color_weight + 1) for each new one; frames older than those
	// kept count as the oldest kept), so this takes that mean to the lighting now.
	LightingChange for_block(const TsdfSurfaceFrames &p_frames, const glm::vec3 &p_point, int p_max_color_weight) const;
	// for_block in two steps, so that the texels of one block share the first: which epochs the
	// block's running mean holds and their shares, then the change at a point.
	struct Mix {
		int count = 0;
		int epoch[TsdfSurfaceFrames::KEPT] = {};
		double share[TsdfSurfaceFrames::KEPT] = {};
	};
	Mix mix(const TsdfSurfaceFrames &p_frames, int p_max_color_weight) const;
	LightingChange for_mix(const Mix &p_mix, const glm::vec3 &p_point) const;
	bool has_field() const; // some epoch's change varies with position
	// Whether any epoch's change varies with position or differs from another's: the texel's
	// point (and block) is needed then.
	bool per_point() const;
};

struct DenseRenderOptions {
	float near_m = 0.02f; // rays start this far from the probe, metres
	float far_m = 4.0f; // and end this far, metres
	// Raycast at 1 / scale of the face size and upsample (nearest, with the coarse render kept
	// where the low-resolution texel missed): fewer rays, blockier dense edges. Measured on the
	// demo's final model (./roomprobe bench slam): a 128² map took 26.8 ms at scale 1, 8.9 at 2,
	// 3.3 at 4, covering the same 54 % of the texels. 1: full size.
	int scale = 2;
	const std::array<float, 256> *lut = nullptr; // 8-bit value -> radiance; null: value / 255
	// The lighting changes applied after the lut, per block by when its surface colours were
	// fused (DenseLightingEpochs, issue #42); the default is the identity.
	DenseLightingEpochs lighting;
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

// The history behind DenseLightingEpochs: which coarse lighting (§4.6) the dense model's frames
// were fused under. The engine records the coarse model's cumulative change after each fused
// frame; a new epoch begins where it has moved by more than rounding since the last epoch's
// (gain 0.5 %, slope 0.005 / m, offset 0.001). Thread-safe: the SLAM worker records while the
// probe worker renders.
class DenseLighting {
public:
	static constexpr size_t MAX_EPOCHS = 1024; // the oldest merge into the next beyond this

	// Colours fused at p_volume_frame (TsdfVolume::frame_count() after the frame) and later are
	// of the lighting p_cumulative (CoarsePipeline::cumulative_lighting then).
	void record(uint32_t p_volume_frame, const LightingChange &p_cumulative);
	// The change each epoch's colours have not seen, the lighting being p_cumulative now.
	DenseLightingEpochs epochs(const LightingChange &p_cumulative) const;
	// render_dense_over with epochs(p_cumulative) as p_options.lighting. With nothing recorded,
	// the colours are taken as of the lighting now.
	DenseRenderStats render_over(const TsdfVolume &p_volume, const LightingChange &p_cumulative, const glm::dvec3 &p_position, DenseRenderOptions p_options,
			Cubemap *io_cubemap, DenseFaceCache *io_cache = nullptr) const;
	// Forgets the history (a new dense model).
	void reset();

private:
	mutable std::mutex mutex;
	std::vector<uint32_t> first_frame;
	std::vector<LightingChange> cumulative; // the coarse model's at each epoch's start
};

// Paints the dense model seen from p_position over io_cubemap (any size; faces CV_32FC3). With
// io_cache, only p_options.faces_per_render faces are raycast now (see DenseFaceCache).
DenseRenderStats render_dense_over(const TsdfVolume &p_volume, const glm::dvec3 &p_position, const DenseRenderOptions &p_options, Cubemap *io_cubemap,
		DenseFaceCache *io_cache = nullptr);

} // namespace roomprobe
