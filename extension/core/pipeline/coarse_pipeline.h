#pragma once
// The coarse-model pipeline (paper §4.3-§4.7) as one plain C++ object, without Godot: a room's
// floorplan and the rig's fisheye in, fisheye frames with their poses in, environment maps out.
//
// Per fisheye frame (add_fisheye_frame):
//   1. occlusion mask (§4.4, coarse/occlusion.h); skipped for a convex floorplan (all visible);
//   2. texture update (§4.3, policy Best, coarse/texture_update.h), from every texel's pixel
//      projected once (project_texels, skipping the tiles the fisheye cannot see); as it passes it
//      gathers the lighting estimate's (old texel, new sample) pairs on a grid of the visible
//      texels observed before, whatever the new sample's quality (LightingPairs);
//   3. lighting change (§4.6, coarse/lighting.h), when enabled: estimated from those pairs (the
//      values from before the update), applied to the observed texels this frame did not update;
//   4. inpainting (§4.5), when enabled: synchronously (TextureInpainter::inpaint), so that the
//      completed texture always belongs to the latest frame (evaluation); or, with inpaint_async
//      (the live path, CoarseRoomModel), off the frame's critical path on the inpainter's worker:
//      each frame requests a completion of its texture and composes the newest finished one under
//      the texels observed now, so new observations show at once and the fill catches up.
// render_cubemap() renders the completed texture (or the raw one) at a probe (§4.7, first pass);
// sh() projects that onto 5 bands of spherical harmonics (§4.8).
//
// Poses: the pipeline takes world_from_fisheye as given. PoseSource says where the caller got it;
// only GroundTruth exists so far (the recording's true RGB-D trajectory through fisheye_pose_at,
// the EVALUATION mode until SLAM is integrated).

#include <coarse/coarse_texture.h>
#include <coarse/inpainting.h>
#include <coarse/lighting.h>
#include <coarse/occlusion.h>
#include <coarse/rgb_texture_update.h>
#include <coarse/texture_update.h>
#include <envmap/coarse_render.h>
#include <envmap/spherical_harmonics.h>
#include <recording/recording_types.h>
#include <rig/rig.h>
#include <room/floorplan.h>
#include <room/room_mesh.h>

#include <memory>
#include <string>

namespace roomprobe {

enum class PoseSource {
	GroundTruth, // the recording's ground-truth RGB-D trajectory -> fisheye_pose_at (evaluation mode)
	Tracked, // DenseSlam's tracked RGB-D trajectory -> fisheye_pose_at (the live mode)
};

struct CoarsePipelineOptions {
	PoseSource pose_source = PoseSource::GroundTruth; // informational: the caller supplies the poses
	bool inpaint = true; // §4.5: complete never-observed texels before rendering
	bool inpaint_async = false; // §4.5 on a worker thread (see step 5 above); false: in add_fisheye_frame
	bool lighting = true; // §4.6: estimate and apply large-scale lighting changes
	LightingModel lighting_model = LightingModel::GAIN_ROBUST; // ADDITIVE_PAPER is the paper's
	double texel_size_m = 0.02; // atlas texel edge, metres (room/room_mesh.h)
	int cubemap_size = 128; // face size of render_cubemap() and sh(), pixels
	TextureUpdateOptions update; // §4.3 settings (policy forced to Best)
	LightingOptions lighting_options; // §4.6 settings (model overridden by lighting_model)
	InpaintingOptions inpainting; // §4.5 settings
	// Texels the fisheye never saw taken from the RGB camera (add_rgb_frame; issue #16). Off by
	// default: the texels are right (docs/FIGURES.md, the error budget), but the maps did not gain, since
	// the dense model already shows what the RGB-D camera saw, and a map without the dense model
	// then shows the real floor where furniture stands.
	bool rgb_texture = false;
	RgbTextureOptions rgb;
	OcclusionOptions occlusion; // §4.4 settings
};

// Wall-clock milliseconds of each stage: of the last frame, and summed over all frames.
struct CoarsePipelineTimings {
	double occlusion_ms = 0.0;
	double lighting_ms = 0.0; // estimating and applying (the pairs are gathered in the update)
	double update_ms = 0.0; // projecting the texels, updating them and gathering the lighting pairs
	double inpaint_ms = 0.0;
	double render_ms = 0.0; // render_cubemap() (the last call / all calls)
	double sh_ms = 0.0; // SH projection in sh()
	double frame_ms = 0.0; // the whole add_fisheye_frame()
	double rgb_ms = 0.0; // add_rgb_frame() (the last call / all calls)
};

struct CoarseFrameStats {
	TextureUpdateStats update;
	LightingChange lighting; // identity when lighting is off or too few samples
	InpaintReport inpaint;
	bool occlusion_skipped = false; // convex room
};

class CoarsePipeline {
public:
	explicit CoarsePipeline(const CoarsePipelineOptions &p_options = CoarsePipelineOptions());
	~CoarsePipeline();
	CoarsePipeline(const CoarsePipeline &) = delete;
	CoarsePipeline &operator=(const CoarsePipeline &) = delete;

	// Builds the room mesh, texel geometry, renderer and inpainter; clears the texture. The error
	// (empty on success) names the problem (invalid floorplan, atlas too large, bad fisheye). A
	// fisheye of size 0 x 0 is none (an RGB-D camera alone, issue #43): the RGB camera is then the
	// model's only eye (add_rgb_view), whatever rgb_texture says.
	std::string configure(const OmniParams &p_fisheye, const Floorplan &p_floorplan);
	std::string configure(const Rig &p_rig, const Floorplan &p_floorplan) { return configure(p_rig.fisheye, p_floorplan); }
	bool is_configured() const { return configured; }
	bool rgb_only() const { return configured && !has_fisheye; }

	// Integrates one fisheye frame (image types as update_coarse_texture accepts) taken at
	// p_world_from_fisheye; a linearised frame's saturation mask (FisheyeFrame::saturated) makes
	// the texture HDR (coarse/texture_update.h). Returns what each stage did; zero stats before
	// configure().
	CoarseFrameStats add_fisheye_frame(const FisheyeFrame &p_frame, const Pose &p_world_from_fisheye);
	// Takes the texels the fisheye has never observed from one RGB-D frame (the RGB image and its
	// registered depth) taken at p_world_from_rgb (coarse/rgb_texture_update.h); p_lut: the RGB
	// camera's value -> radiance (null: value / 255). No effect with rgb_texture off. The completed
	// texture follows at the next fisheye frame.
	RgbTextureStats add_rgb_frame(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut);
	// Without a fisheye (rgb_only()): one RGB-D frame as the model's view, as add_fisheye_frame
	// is with one: the texture update from the RGB camera, the lighting change (§4.6) from the
	// texels it sees again (their held value against this view's), applied to those it did not
	// update, then the inpainting. Zero stats with a fisheye.
	CoarseFrameStats add_rgb_view(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut);

	// The environment map at p_position (world metres) of the completed texture (the raw one
	// when inpainting is off or p_completed is false). Size 0: options.cubemap_size.
	Cubemap render_cubemap(const glm::dvec3 &p_position, bool p_completed = true, int p_size = 0);
	ShCoefficients sh(const glm::dvec3 &p_position);
	// With inpaint_async: waits for the worker's newest completion and composes it (end of a
	// recording, tests). No effect otherwise.
	void finish_inpainting();

	// A new room keeps what the old one observed (issue #18: the room found from the sweep moves
	// its walls as it refines): every texel of this room's surface whose point, seen in p_old's
	// room (p_new_from_old maps p_old's room frame into this one's), lies within p_tolerance_m of
	// p_old's surface of the same kind facing the same way takes that texel's observation, and
	// the frame count and lighting changes carry over. Returns the share of this room's surface
	// texels that took an observation (0 to 1; 0: nothing carried, the frame count stays 0).
	// The completed texture follows at the next fisheye frame.
	double carry_texture(const CoarsePipeline &p_old, const Pose &p_new_from_old, double p_tolerance_m);

	// Only observations (CoarseTexture::color keeps no inpainted values).
	const CoarseTexture &texture() const { return coarse; }
	// The inpainted colour when inpainting is on and a frame was added, else texture().color.
	const cv::Mat &completed_color() const;
	const RoomMesh &mesh() const { return room; }
	const CoarsePipelineOptions &options() const { return opts; }
	size_t frame_count() const { return frames; }
	const CoarsePipelineTimings &last_timings() const { return last; }
	const CoarsePipelineTimings &total_timings() const { return total; }
	// Every lighting change applied so far, composed (identity at first): what a colour observed
	// at the start has become. The dense model's colours take the part since they were observed
	// (envmap/dense_render.h).
	const LightingChange &cumulative_lighting() const { return cumulative; }

private:
	void compose_completed();
	RgbTextureStats rgb_update(const RgbdFrame &p_frame, const PinholeParams &p_camera, const Pose &p_world_from_rgb, const ResponseCurve *p_lut,
			LightingPairs *r_pairs);
	// The lighting change from lighting_pairs (when p_estimate), applied to the texels the view did
	// not update and composed into cumulative.
	void change_lighting(bool p_estimate, CoarseFrameStats *io_stats, CoarsePipelineTimings *io_timings);
	// The frame's last stage for both kinds of view: the inpainting (§4.5), the counts and timings.
	void finish_frame(CoarsePipelineTimings *io_timings, CoarseFrameStats *io_stats, double p_frame_start_ms_ago);

	CoarsePipelineOptions opts;
	bool configured = false;
	bool has_fisheye = true;
	bool convex = false;
	OmniParams fisheye;
	Floorplan floorplan;
	RoomMesh room;
	TexelGeometry geometry;
	CoarseTexture coarse;
	cv::Mat completed;
	cv::Mat inpainted; // inpaint_async: the worker's newest completion (of an older texture)
	TexelProjection projection; // this frame's texel pixels (kept: no allocation a frame)
	cv::Mat mask; // this frame's occlusion mask (kept)
	cv::Mat rgb_fresh; // CV_8UC1: texels the RGB camera updated since the last fisheye frame
	LightingPairs lighting_pairs; // the lighting estimate's pairs, kept between frames (no allocation a frame)
	std::unique_ptr<CoarseCubemapRenderer> renderer;
	std::unique_ptr<TextureInpainter> inpainter;
	size_t frames = 0;
	LightingChange cumulative;
	CoarsePipelineTimings last;
	CoarsePipelineTimings total;
};

} // namespace roomprobe
