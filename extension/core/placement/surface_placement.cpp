#include "surface_placement.h"

#include <glm/geometric.hpp>

namespace roomprobe {

namespace {

std::string build_scene(const std::vector<float> &p_xyz, const std::vector<uint32_t> &p_indices, std::unique_ptr<EmbreeTriangleScene> *r_scene) {
	if (p_indices.empty()) {
		r_scene->reset();
		return "";
	}
	auto scene = std::make_unique<EmbreeTriangleScene>();
	const std::string error = scene->build(p_xyz, p_indices, false);
	if (error.empty()) {
		*r_scene = std::move(scene);
	}
	return error;
}

} // namespace

std::string SurfacePlacer::set_coarse(const RoomMesh &p_room, const Pose &p_world_from_room) {
	std::vector<float> xyz;
	xyz.reserve(p_room.positions.size() * 3);
	for (const Vec3f &v : p_room.positions) {
		const glm::dvec3 world = transform_point(p_world_from_room, glm::dvec3(v.x, v.y, v.z));
		xyz.insert(xyz.end(), { float(world.x), float(world.y), float(world.z) });
	}
	return build_scene(xyz, p_room.indices, &coarse);
}

std::string SurfacePlacer::set_dense(const TriangleMesh &p_mesh) {
	std::shared_ptr<const EmbreeTriangleScene> scene;
	const std::string error = build_dense(p_mesh, &scene);
	if (error.empty()) {
		dense = std::move(scene);
	}
	return error;
}

std::string SurfacePlacer::build_dense(const TriangleMesh &p_mesh, std::shared_ptr<const EmbreeTriangleScene> *r_scene) {
	std::vector<float> xyz;
	xyz.reserve(p_mesh.vertices.size() * 3);
	for (const glm::vec3 &v : p_mesh.vertices) {
		xyz.insert(xyz.end(), { v.x, v.y, v.z });
	}
	std::unique_ptr<EmbreeTriangleScene> scene;
	const std::string error = build_scene(xyz, p_mesh.indices, &scene);
	if (error.empty()) {
		*r_scene = std::move(scene);
	}
	return error;
}

PlacementHit SurfacePlacer::cast(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_max_distance_m) const {
	PlacementHit best;
	const double length = glm::length(p_direction);
	if (!(length > 0.0)) {
		return best;
	}
	const glm::dvec3 direction = p_direction / length;
	const std::pair<const EmbreeTriangleScene *, PlacementSurface> scenes[] = { { dense.get(), PlacementSurface::Dense }, { coarse.get(), PlacementSurface::Coarse } };
	double limit = p_max_distance_m;
	for (const auto &[scene, surface] : scenes) {
		EmbreeTriangleScene::RayHit hit;
		if (scene == nullptr || !scene->intersect(p_origin, direction, 0.0, limit, &hit)) {
			continue;
		}
		glm::dvec3 normal = glm::normalize(glm::dvec3(hit.geometric_normal));
		if (glm::dot(normal, direction) > 0.0) {
			normal = -normal; // both sides of a surface can be placed on
		}
		limit = hit.t;
		best.surface = surface;
		best.distance_m = hit.t;
		best.point = p_origin + double(hit.t) * direction;
		best.normal = normal;
	}
	return best;
}

} // namespace roomprobe
