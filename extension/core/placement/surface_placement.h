#pragma once
// Scene placement by Embree ray queries: where a ray (from the screen, or any 3-D ray) meets the
// real room's surfaces, the dense model's mesh (slam/marching_cubes.h) or the coarse room prism
// (room/room_mesh.h), with the surface normal there, so that a designer or a player can put a
// virtual object on the real table. The nearer of the two models wins.

#include <io/embree_scene.h>
#include <math/pose.h>
#include <room/room_mesh.h>
#include <slam/marching_cubes.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>

namespace roomprobe {

enum class PlacementSurface {
	None,
	Dense, // the dense model's mesh
	Coarse, // the room prism (walls, floor, ceiling)
};

struct PlacementHit {
	PlacementSurface surface = PlacementSurface::None;
	glm::dvec3 point = glm::dvec3(0.0); // world metres
	glm::dvec3 normal = glm::dvec3(0.0); // unit, facing the ray's origin
	double distance_m = 0.0; // along the (normalised) ray
};

class SurfacePlacer {
public:
	// Each scene is rebuilt only when given a mesh (the dense one as it grows). The coarse room
	// mesh is in the room's frame; p_world_from_room places it in the world (its node's transform,
	// or the room found from the sweep). Return "" or what Embree reported.
	std::string set_coarse(const RoomMesh &p_room, const Pose &p_world_from_room = Pose());
	std::string set_dense(const TriangleMesh &p_mesh);
	// set_dense in two steps, so that the slow one (hundreds of milliseconds for a room's mesh)
	// runs outside the lock that guards cast: build_dense makes the scene (null for an empty
	// mesh; r_scene untouched on an error), set_dense_scene puts it in.
	static std::string build_dense(const TriangleMesh &p_mesh, std::shared_ptr<const EmbreeTriangleScene> *r_scene);
	void set_dense_scene(std::shared_ptr<const EmbreeTriangleScene> p_scene) { dense = std::move(p_scene); }
	void clear_dense() { dense.reset(); }
	void clear_coarse() { coarse.reset(); }

	// The nearest surface along p_origin + t * p_direction, 0 < t <= p_max_distance_m (the
	// direction need not be unit length; distances are in metres all the same).
	PlacementHit cast(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_max_distance_m = 100.0) const;

private:
	std::unique_ptr<EmbreeTriangleScene> coarse;
	std::shared_ptr<const EmbreeTriangleScene> dense;
};

} // namespace roomprobe
