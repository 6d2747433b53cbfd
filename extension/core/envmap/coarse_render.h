#pragma once
// Renders the textured coarse model (the floorplan prism and its atlas, room/room_mesh.h,
// coarse/coarse_texture.h) into a cubemap at a probe position (paper §4.7, first pass).
//
// The paper rasterises the six faces on the GPU; here every face pixel's ray (cubemap_direction)
// is intersected with the prism exactly instead: the floor (y = 0) and ceiling (y = height)
// planes with a point-in-polygon test, and each wall as a segment in (x, z) with a height check;
// the nearest hit wins. The hit is mapped into its chart's atlas rect (the inverse of Chart's
// texel mapping) and the atlas is sampled bilinearly, only from texels on that chart's surface
// (texel_to_world succeeds), so nothing bleeds in from padding, the rounding margin or, on the
// floor and ceiling, from outside the polygon.

#include "coarse_render_gpu.h"
#include "cubemap.h"

#include <coarse/coarse_texture.h>
#include <room/room_mesh.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <vector>

namespace roomprobe {

// The nearest surface of the room along a ray.
struct RoomRayHit {
	double distance = 0.0; // along the (normalised) ray direction, metres
	glm::dvec3 point = glm::dvec3(0.0); // world metres
	int chart = -1; // into RoomMesh::charts (walls 0..n-1, floor n, ceiling n + 1)
	glm::dvec2 atlas = glm::dvec2(0.0); // continuous atlas position, texel units (texel (x, y) has centre (x + 0.5, y + 0.5))
};

// Intersects the ray p_origin + t p_direction (t > 0; p_direction need not be normalised) with
// the room prism of p_mesh. False when it hits nothing (an origin outside the room can miss).
bool intersect_room(const RoomMesh &p_mesh, const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, RoomRayHit *r_hit);

// Renders a coarse model into cubemaps. Build once per room mesh (it caches which atlas texels
// lie on the surface, p_mesh's atlas size in bytes), then render any number of probes. The
// mesh must outlive the renderer. A compute device, when set, gathers the faces (set_compute).
class CoarseCubemapRenderer {
public:
	explicit CoarseCubemapRenderer(const RoomMesh &p_mesh);

	// The cubemap seen from p_position (world metres, inside the room) through the atlas
	// p_atlas_color (CV_32FC3, the mesh's atlas size; CoarseTexture::color). Directions that hit
	// nothing (a position outside the room) are black. Returns an invalid (size 0) cubemap when
	// the atlas has the wrong size or type. The map's distance_m holds each ray's hit distance.
	// p_room_from_world: the room's orientation in the world when the two differ (a room found
	// from the sweep, issue #18, or a CoarseRoomModel node turned): the faces stay the world's,
	// their rays are turned into the room's frame. p_position is then in the room's frame too.
	// Parallel over face rows (TBB).
	// The rays and taps depend only on the position and size, not on the atlas: they are kept for
	// the last MAX_CACHED_LOOKUPS (position, size) pairs (36 bytes a texel with the distance: 14 MiB at 256^2), so a
	// probe that does not move costs a gather of four taps a texel. Safe to call from any thread.
	// p_atlas_published: the atlas is never written again (the engine's coarse snapshots), so a
	// compute device keeps it between maps instead of uploading it for each (set_compute).
	Cubemap render(const cv::Mat &p_atlas_color, const glm::dvec3 &p_position, int p_size = 256,
			const glm::dquat &p_room_from_world = glm::dquat(1.0, 0.0, 0.0, 0.0), bool p_atlas_published = false) const;
	Cubemap render(const CoarseTexture &p_texture, const glm::dvec3 &p_position, int p_size = 256) const {
		return render(p_texture.color, p_position, p_size);
	}

	// The same rays and taps over a one-channel atlas (CV_32FC1, the mesh's atlas size: a mask):
	// one CV_32FC1 image per face, 0 where a ray hits nothing. Empty images when the atlas does
	// not fit.
	std::array<cv::Mat, 6> render_channel(const cv::Mat &p_atlas, const glm::dvec3 &p_position, int p_size,
			const glm::dquat &p_room_from_world = glm::dquat(1.0, 0.0, 0.0, 0.0), bool p_atlas_published = false) const;

	// The gather on a Vulkan compute device (issue #40; coarse_render_gpu.h): the same faces, bit for
	// bit. Null: the CPU. A gather the device fails is done on the CPU, and compute_problem() says
	// why (empty while the device works).
	void set_compute(std::shared_ptr<ComputeDevice> p_device);
	bool gathers_on_gpu() const;
	std::string compute_problem() const;

	// Whether atlas texel (x, y) lies on the room surface (texel_to_world succeeds).
	bool texel_on_surface(int p_x, int p_y) const;

	static constexpr int MAX_CACHED_LOOKUPS = 8;

private:
	// The taps of one cubemap texel: the atlas at continuous atlas position (texel units, see
	// RoomRayHit) on its chart, bilinear over the chart's surface texels, clamped to the chart:
	// up to four atlas texels, the first a used one, the others with their share of the used
	// taps' weight (0 for the unused, which repeat the first texel).
	struct Taps {
		uint32_t index[4] = { 0, 0, 0, 0 }; // atlas texels, row-major
		float hit = 0.0f; // 1 where the ray hit the room, else 0 (the texel is black)
		float weight[3] = { 0.0f, 0.0f, 0.0f }; // of taps 1..3, normalised
	};
	struct Lookup {
		glm::dvec3 position = glm::dvec3(0.0);
		int size = 0;
		glm::dquat room_from_world = glm::dquat(1.0, 0.0, 0.0, 0.0);
		std::vector<Taps> taps; // face-major, then rows, then columns
		std::vector<float> distance_m; // the same order: the ray's hit distance (0: none)
	};
	Taps texel_taps(int p_chart, const glm::dvec2 &p_atlas) const;
	template <int N>
	static cv::Vec<float, N> gather(const cv::Vec<float, N> *p_atlas, const Taps &p_taps);
	// Every texel of every face of p_lookup from p_atlas (N float channels) into r_faces (made).
	template <int N>
	static void gather_faces(const Lookup &p_lookup, const cv::Mat &p_atlas, std::array<cv::Mat, 6> *r_faces);
	std::shared_ptr<const Lookup> lookup(const glm::dvec3 &p_position, int p_size, const glm::dquat &p_room_from_world) const;
	// The faces gathered on the compute device; false: none, or it failed (then on the CPU).
	bool gather_on_gpu(const std::shared_ptr<const Lookup> &p_lookup, const cv::Mat &p_atlas, bool p_published, std::array<cv::Mat, 6> *r_faces) const;

	const RoomMesh &mesh;
	std::vector<uint8_t> on_surface; // atlas_width * atlas_height, row-major
	mutable std::mutex lookup_mutex;
	mutable std::list<std::shared_ptr<const Lookup>> lookups; // most recently used first
	mutable std::mutex gpu_mutex; // the device's buffers: one gather at a time
	std::unique_ptr<CoarseGatherGpu> gpu;
	mutable std::string gpu_problem;
};

} // namespace roomprobe
