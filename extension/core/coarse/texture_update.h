#pragma once
// Updating the coarse model's texture from a fisheye frame (paper §4.3): every atlas texel on the
// room's surface is taken to the world, into the fisheye's frame, projected with the unified
// omnidirectional model (camera/omni_camera.h) and, where the fisheye sees it and the occlusion
// mask (coarse/occlusion.h, §4.4) lets it, the image is sampled there. Rather than the paper's
// "latest frame wins", the texel keeps its BEST observation so far (viewing angle, distance,
// position in the image circle), still following the scene when seen about as well again.

#include <io/opencv.h>

#include "coarse_texture.h"
#include "lighting.h"

#include <camera/camera_params.h>
#include <math/pose.h>
#include <room/room_mesh.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace roomprobe {

// Each atlas texel's world point and inward normal (room/room_mesh.h texel_to_world), computed
// once per mesh and reused by every frame (and by the occlusion masks).
struct TexelGeometry {
	int width = 0; // atlas width, texels
	int height = 0; // atlas height, texels
	std::vector<glm::dvec3> points; // world point of texel (x, y) at [y * width + x], metres
	std::vector<glm::dvec3> normals; // unit inward normal, same indexing
	std::vector<int> charts; // chart index (into RoomMesh::charts), -1 where the texel is not on the surface
	size_t surface_texels = 0; // texels with charts[i] >= 0
	// Square tiles of the atlas, for skipping the ones a frame cannot see (project_texels).
	static constexpr int tile_size = 16; // texels
	int tiles_x = 0, tiles_y = 0; // tile (tx, ty) covers texels [tx, ty] * tile_size + [0, tile_size)
	std::vector<glm::dvec3> tile_centres; // bounding sphere of the tile's surface points, world metres, at [ty * tiles_x + tx]
	std::vector<double> tile_radii; // its radius, metres; < 0: no surface texel in the tile
	std::vector<int> tile_charts; // the one chart all its surface texels lie on, else -1
	std::vector<glm::dvec3> tile_normals; // that chart's unit inward normal (a surface texel's)

	bool on_surface(int p_x, int p_y) const { return charts[size_t(p_y) * width + p_x] >= 0; }
};

TexelGeometry make_texel_geometry(const RoomMesh &p_mesh);

enum class TextureUpdatePolicy {
	Best, // keep the best-quality observation (replace when the new one is nearly as good or better)
	Last, // the paper's: every valid observation overwrites the texel (for comparison)
};

// Settings of update_coarse_texture().
struct TextureUpdateOptions {
	TextureUpdatePolicy policy = TextureUpdatePolicy::Best;
	// Best: a new observation replaces the kept one when its quality >= kept * (1 - epsilon), so
	// the texture follows the scene (lighting changes, §4.6) when it is seen about as well again.
	// Unitless, in [0, 1): 0 only strictly-as-good views replace; 0.25 a view 25 % worse does too.
	// The reference is the best quality ever seen at the texel (io_texture->quality holds it), so a
	// run of slightly worse views cannot ratchet it down. Measured on a 20-frame two_rooms sequence
	// (tests/core/test_coarse_update_texture.cpp): MAE falls with epsilon towards 0 (0: -6 % against
	// "last" with the footprint quality, -10 % with the closed form); 0.05 keeps some following.
	double replace_epsilon = 0.05;
	// Texels seen more obliquely than this (cos of the angle between the inward normal and the
	// direction to the camera) are not updated at all: at grazing angles a texel covers a sliver
	// of a pixel. Unitless, in [0, 1).
	double min_cos_view = 0.1;
	// Distance below which nearer does not count as better (the fisheye's blur and the texel size
	// dominate there), metres; > 0.
	double min_distance_m = 0.5;
	// The fisheye blurs (and its pixels cover more solid angle) towards the image circle's edge:
	// quality is multiplied by 1 - edge_penalty * r^2, r = distance from the circle centre /
	// circle radius (image half-diagonal when there is no circle). Unitless, in [0, 1).
	double edge_penalty = 0.5;
	// true: quality is the texel's area in the image (pixels^2, from projecting its edges with the
	// camera model: viewing angle, distance and the lens's distortion in one), times the edge
	// penalty, instead of observation_quality()'s closed form. Costs two more projections a texel.
	bool footprint_quality = true;
	// Pixels this close to the image circle's rim (or the image border) are not sampled (the
	// bilinear footprint would reach the black outside), pixels; >= 0.
	double rim_margin_px = 1.5;
};

// Quality of observing a surface point: cos_view / max(distance, min_distance)^2 * (1 -
// edge_penalty * r^2), i.e. proportional to the texel's footprint in the image (pixels per
// texel) discounted towards the edge; 0 when cos_view < min_cos_view. Units: 1 / m^2.
double observation_quality(double p_cos_view, double p_distance_m, double p_radius_fraction, const TextureUpdateOptions &p_options);

struct TextureUpdateStats {
	size_t texels_visible = 0; // surface texels the fisheye sees in this frame (in the circle, in front, unmasked)
	size_t texels_updated = 0; // of those, how many took the new observation
	double seconds = 0.0; // wall-clock time of the update
};

// Each atlas texel's pixel in one fisheye frame, projected once (project_omni) and read by the
// lighting estimate's samples and the texture update of that frame. The update then takes a
// texel's footprint from its neighbours' pixels: the texel one step along its chart's u (v) axis
// is the next texel along atlas x (y) on the same chart, so no further projection is needed
// except at a chart's edge.
// Tiles the fisheye cannot see (all their points outside the lens's cone of view, or behind their
// one chart's plane) are skipped: their texels' pixels are not written, and the readers skip them.
struct TexelProjection {
	cv::Mat pixels; // CV_64FC2, atlas-sized: texel (x, y)'s pixel; NaN where it is not on the surface or project_omni does not see it
	std::vector<uint8_t> tile_seen; // per TexelGeometry tile: 0 when skipped (its pixels are stale)
	// The cone the lens sees within, from its image circle (or image border), kept for the lens it
	// was found for.
	OmniParams cone_lens;
	double cone_cos = -2.0; // cos of the cone's half angle; -2: no cone (nothing is skipped by angle)

	bool seen(const TexelGeometry &p_geometry, int p_x, int p_y) const {
		return tile_seen[size_t(p_y / TexelGeometry::tile_size) * p_geometry.tiles_x + p_x / TexelGeometry::tile_size] != 0;
	}
};

// Fills io_projection for the fisheye at p_world_from_fisheye (allocates only when the atlas size
// changes). Parallel over rows.
void project_texels(const TexelGeometry &p_geometry, const OmniParams &p_params, const Pose &p_world_from_fisheye, TexelProjection *io_projection);

// The fisheye's colour at the texels update_coarse_texture would see this frame (its visibility
// test and bilinear sample, whatever their quality), only on the grid x % p_step == 0,
// y % p_step == 0 and only where p_only (CV_8UC1, atlas-sized) is non-zero: the lighting
// estimate's new values (§4.6) without a copy of the atlas. r_samples (CV_32FC3) is written
// where r_visible (CV_8UC1, zero elsewhere) is 255; both are atlas-sized. Parallel over rows.
void sample_coarse_texels(const TexelGeometry &p_geometry, const OmniParams &p_params, const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image,
		const cv::Mat *p_visibility_mask, const cv::Mat &p_only, int p_step, const TextureUpdateOptions &p_options, cv::Mat *r_samples, cv::Mat *r_visible);
// The same from the frame's projection (project_texels with the same fisheye and pose).
void sample_coarse_texels(const TexelGeometry &p_geometry, const TexelProjection &p_projection, const OmniParams &p_params, const Pose &p_world_from_fisheye,
		const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, const cv::Mat &p_only, int p_step, const TextureUpdateOptions &p_options,
		cv::Mat *r_samples, cv::Mat *r_visible);

// Updates io_texture (from make_coarse_texture(p_mesh)) with one fisheye frame.
// p_fisheye_image: CV_8UC1 (grey, copied to R, G, B), CV_8UC3 (R, G, B; value / 255) or CV_32FC3
// (R, G, B radiance as is), p_params' size. p_visibility_mask: CV_8UC1 atlas-sized, 255 where
// the fisheye can see the texel (occlusion.h); null: all visible. Clears io_texture->updated,
// then sets it (255) on every texel that took the new observation, with observed and quality.
// Parallel over atlas rows. Returns zero stats when the inputs do not fit together.
TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const OmniParams &p_params,
		const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask,
		CoarseTexture *io_texture, const TextureUpdateOptions &p_options = TextureUpdateOptions());
// The lighting estimate's (old texel, new sample) pairs, gathered by the update as it passes:
// the texels on the grid x % step == 0, y % step == 0 that were observed before this frame and
// that the frame sees (sample_coarse_texels' set and values, whatever their quality), the old
// value read before the update writes. Kept between frames (no allocation a frame).
struct LightingPairs {
	int step = 2; // >= 1
	std::vector<std::vector<LightingSample>> rows; // per grid row
	std::vector<LightingSample> all; // gather()'s, in row-major order

	// Empties the rows for an atlas p_height texels high (one row a step); returns the step.
	int begin(int p_height);
	// The rows' pairs in row-major order, into all.
	const std::vector<LightingSample> &gather();
};

// The same from the frame's projection (project_texels with the same fisheye and pose): one
// projection a texel instead of three; the same result up to rounding. With r_pairs, also
// gathers the lighting estimate's pairs (its step is read, its rows filled), leaving out texels
// whose kept or new value is clipped.
// p_saturated (CV_8UC1, the image's size, 255 where a channel was clipped: LinearFrame's mask)
// makes the update HDR: a sample touching a clipped pixel is a lower bound, which never replaces
// an unclipped observation, except one it proves wrong (the bound over 1.25 times the kept
// value: the scene has changed, e.g. a light came on); an unclipped one always replaces a clipped
// one (so a texel clipped at a long exposure is filled from a shorter one); between two clipped
// ones the brighter stays.
// io_texture->saturated records which texels hold a clipped value. Null: nothing is clipped.
TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const TexelProjection &p_projection, const OmniParams &p_params,
		const Pose &p_world_from_fisheye, const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, CoarseTexture *io_texture,
		const TextureUpdateOptions &p_options = TextureUpdateOptions(), LightingPairs *r_pairs = nullptr, const cv::Mat *p_saturated = nullptr);

// The same, computing the texel geometry on the fly (slower: prefer the overload above per frame).
TextureUpdateStats update_coarse_texture(const RoomMesh &p_mesh, const OmniParams &p_params, const Pose &p_world_from_fisheye,
		const cv::Mat &p_fisheye_image, const cv::Mat *p_visibility_mask, CoarseTexture *io_texture,
		const TextureUpdateOptions &p_options = TextureUpdateOptions());

} // namespace roomprobe
