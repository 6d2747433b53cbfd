#pragma once
// Virtual objects drawn into the probes' maps (paper §4.7, last paragraph: "if others were
// present, they could also be rendered into the cubemap at this stage, allowing the environment
// map to capture the complete mixed reality scene"). After the room is rendered into a probe's
// map, the other virtual objects are ray-traced over it with Embree from the probe's position, so
// a mirror sphere reflects the bottle beside it, and a shadow catcher (prt/contact_shadow.h)
// darkens the real table in the reflections as it does in the camera image (Figure 11).
//
// Each object is shaded with what its own material would show, from what the looking probe
// knows: diffuse objects by the probe's SH irradiance at their normal, mirrors and glass by the
// probe's previous map (one map behind; the light at the probe, not at the object: a
// one-bounce approximation). Real surfaces never hide a virtual object (the objects stand in
// the room, in front of its walls).

#include "prt_transfer.h"

#include <envmap/cubemap.h>
#include <envmap/map_overlay.h>
#include <envmap/spherical_harmonics.h>
#include <io/embree_scene.h>

#include <glm/mat3x3.hpp>

#include <memory>
#include <string>
#include <vector>

namespace roomprobe {

enum class VirtualLook {
	Diffuse, // albedo / pi x the SH irradiance at the normal
	Mirror, // tint x the previous map along the reflection
	Glass, // Schlick's Fresnel between the reflection and the previous map through one refraction
	ShadowCatcher, // not drawn: multiplies the room behind it by its contact-shadow ratio
};

struct VirtualObject {
	VirtualLook look = VirtualLook::Diffuse;
	PrtMesh mesh; // world metres, world normals
	glm::dvec3 color = glm::dvec3(0.8); // linear: Diffuse's albedo, Mirror's and Glass's tint
	double ior = 1.5; // Glass
	// ShadowCatcher: per vertex of mesh, the transfer of the supporting plane with the object as
	// occluder (PRTTransfer), in the frame whose world basis is transfer_frame; and the plane's
	// normal (world) for the irradiance without the object.
	std::vector<TransferVector> transfer;
	glm::dmat3 transfer_frame = glm::dmat3(1.0);
	glm::dvec3 plane_normal = glm::dvec3(0.0, 1.0, 0.0);
};

// The objects a probe draws (never its own object: the caller leaves it out), with their Embree
// scenes. Immutable once made; shared with the engine's worker.
class VirtualScene final : public MapOverlay {
public:
	// "" or what is wrong with which object (by its index in p_objects).
	static std::string make(std::vector<VirtualObject> p_objects, std::shared_ptr<const VirtualScene> *r_scene);

	size_t object_count() const override { return objects.size(); }

	// Draws the objects into io_map as seen from p_position_m: p_light is the SH radiance at the
	// probe (its previous map's, or this map's before the objects), p_previous its previous map
	// (null: mirrors and glass fall back to diffuse shading with their tint). Only the texels
	// within the objects' bounding sphere are traced.
	VirtualDrawStats draw(const glm::dvec3 &p_position_m, const ShCoefficients &p_light, const Cubemap *p_previous, Cubemap *io_map) const override;

private:
	VirtualScene() = default;
	std::vector<VirtualObject> objects;
	// All solid objects' triangles in one scene, all catchers' in another; per triangle, its
	// object and its first index into that object's mesh.
	EmbreeTriangleScene solids, catchers;
	std::vector<uint32_t> solid_object, solid_triangle, catcher_object, catcher_triangle;
	glm::dvec3 bound_centre = glm::dvec3(0.0);
	double bound_radius = 0.0;
};

} // namespace roomprobe
