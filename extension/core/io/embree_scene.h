#pragma once
// One triangle mesh in an Embree scene, for the core's ray queries (occlusion checks, the
// synthetic rig). RAII: the device and the scene are released with the object.

#include <embree4/rtcore.h>

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
	RTCScene get() const { return scene; }

private:
	RTCDevice device = nullptr;
	RTCScene scene = nullptr;
};

} // namespace roomprobe
