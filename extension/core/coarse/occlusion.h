#pragma once
// Occlusion in the coarse model (paper §4.4): which atlas texels the fisheye can see. The room is
// a right prism with full-height walls, so a surface point is visible from the fisheye exactly
// when its floorplan position (x, z) is visible from the fisheye's (x, z) inside the floorplan
// polygon: a 2-D visibility polygon (an angular sweep over the corners, visibility_polygon.cpp)
// decides it.
// The paper rasterises that polygon into texture space on the GPU; here each texel is tested
// against it (parallel over rows), which gives the same mask. An Embree ray caster validates it
// (and can add occluders the floorplan does not know).

#include <io/opencv.h>

#include "texture_update.h"

#include <room/floorplan.h>
#include <room/room_mesh.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <memory>
#include <string>
#include <vector>

namespace roomprobe {

// True when the floorplan polygon is convex (collinear corners allowed): every point of the room
// then sees every other, and no occlusion mask is needed. Either orientation; meant for
// floorplans that pass check_floorplan().
bool floorplan_is_convex(const Floorplan &p_floorplan);

// The region of the floorplan visible from a viewpoint, in (x, z) metres.
struct VisibilityPolygon {
	bool ok = false; // false: the viewpoint is not strictly inside the floorplan, or the floorplan is not simple
	std::string error; // why, when ok is false
	std::vector<glm::dvec2> points; // counter-clockwise in (x, z) (floorplan.h's convention), closed implicitly
};

// The union, over the wedges between the directions to consecutive corners, of the triangle the
// nearest wall closes: regularised (no needles along a ray that grazes a corner). Decisions use
// CGAL's exact predicates; points are computed in doubles. Either orientation; consecutive
// repeated points are dropped. p_viewpoint_xz: world (x, z), metres.
VisibilityPolygon visibility_polygon(const Floorplan &p_floorplan, const glm::dvec2 &p_viewpoint_xz);

// Whether a point (x, z) lies inside p_polygon (boundary points count as either).
bool point_in_polygon(const std::vector<glm::dvec2> &p_polygon, const glm::dvec2 &p_point);

struct OcclusionOptions {
	// Wall texels lie ON the floorplan's edges, i.e. on the visibility polygon's boundary where
	// visible: they are tested this far inside the room along their inward normal, metres; > 0
	// and well below the texel size.
	double wall_inset_m = 1e-3;
	// Floorplans that floorplan_is_convex() accepts get an all-visible mask without a visibility polygon.
	bool skip_convex = true;
};

// CV_8UC1, atlas-sized: 255 on the surface texels the fisheye at p_fisheye_position (world, metres)
// can see, 0 elsewhere (occluded, or not on the surface). When the viewpoint is not inside the
// floorplan nothing is visible (all 0): the pose is then not trusted to update the texture.
// Optionally returns the visibility polygon (empty and ok for a skipped convex room).
cv::Mat occlusion_mask(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position,
		const OcclusionOptions &p_options = OcclusionOptions(), VisibilityPolygon *r_polygon = nullptr);
// The same into r_mask (allocated only when the atlas size changes), tested only in the tiles
// p_projection sees (project_texels for this frame; 0 elsewhere: the update skips those tiles).
// No convex-room shortcut: the caller skips the mask for a convex room.
void occlusion_mask(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position, const TexelProjection &p_projection,
		cv::Mat *r_mask, const OcclusionOptions &p_options = OcclusionOptions());

// Validation (and extra occluders): Embree rays from the fisheye centre to each texel centre over
// the coarse mesh plus optional extra triangles. Builds the Embree scene once; thread-safe queries.
class EmbreeOcclusion {
public:
	// p_extra_triangles: world points, three a triangle (either winding), metres.
	explicit EmbreeOcclusion(const RoomMesh &p_mesh, const std::vector<glm::dvec3> &p_extra_triangles = {});
	~EmbreeOcclusion();
	EmbreeOcclusion(const EmbreeOcclusion &) = delete;
	EmbreeOcclusion &operator=(const EmbreeOcclusion &) = delete;

	bool ok() const { return error_message.empty(); }
	const std::string &error() const { return error_message; }

	// As occlusion_mask(): 255 where no surface lies between the fisheye and the texel centre,
	// closer than the texel by more than p_epsilon_m (metres).
	cv::Mat mask(const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position, double p_epsilon_m = 1e-3) const;

private:
	struct Embree;
	std::unique_ptr<Embree> embree;
	std::string error_message;
};

// One-shot convenience over EmbreeOcclusion (builds the scene every call). Empty Mat on failure.
cv::Mat occlusion_mask_embree(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position,
		const std::vector<glm::dvec3> &p_extra_triangles = {}, double p_epsilon_m = 1e-3);

} // namespace roomprobe
