#pragma once
// One triangle mesh in an Embree scene, for the core's ray queries (occlusion checks, the
// synthetic rig). RAII: the device and the scene are released with the object.
//
// Embree's own types stay in embree_scene.cpp, the one file that talks to Embree: it builds
// against Embree 4 (the toolchain) and Embree 3 (Debian 12, the shipped library's baseline).

#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

class EmbreeTriangleScene {
public:
	EmbreeTriangleScene() = default;
	~EmbreeTriangleScene();
	EmbreeTriangleScene(const EmbreeTriangleScene &) = delete;
	EmbreeTriangleScene &operator=(const EmbreeTriangleScene &) = delete;

	// Builds the scene from p_xyz (3 floats a vertex, metres) and p_indices (3 a triangle).
	// p_high_quality trades build time for faster rays. Returns "" or what went wrong; on
	// failure get() is null.
	std::string build(const std::vector<float> &p_xyz, const std::vector<uint32_t> &p_indices, bool p_high_quality);
	bool built() const { return scene != nullptr; }

	// The nearest triangle along origin + t * direction, t in (t_near, t_far): r_t, r_triangle and
	// the unnormalised geometric normal (Embree's Ng, on the side the winding gives). False on a
	// miss or before build(). Thread-safe once built.
	struct RayHit {
		float t = 0.0f;
		uint32_t triangle = 0;
		glm::vec3 geometric_normal = glm::vec3(0.0f);
		float u = 0.0f, v = 0.0f; // barycentrics: the hit is (1 - u - v) v0 + u v1 + v v2
	};
	bool intersect(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far, RayHit *r_hit) const;
	// Whether anything lies along origin + t * direction, t in (t_near, t_far) (Embree's any-hit
	// query, cheaper than intersect). False before build(). Thread-safe once built.
	bool occluded(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) const;

private:
	// Embree's RTCDevice and RTCScene (opaque pointers in both versions).
	void *device = nullptr;
	void *scene = nullptr;
};

} // namespace roomprobe
