#pragma once
// A MeshInstance3D as a virtual object drawn into other probes' maps (prt/virtual_objects.h):
// its mesh in world coordinates and its look, read from its material:
// - RoomProbe's mirror.gdshader and rough_metal.gdshader: a mirror with their `tint`;
// - glass.gdshader: glass with its `ior` and `tint`;
// - contact_shadow.gdshader: a shadow catcher, its `transfer` and `plane_normal`;
// - prt_diffuse.gdshader and sh_diffuse.gdshader: diffuse with their `albedo` (sRGB);
// - a BaseMaterial3D: a mirror when metallic >= 0.5 and roughness < 0.35 (albedo as tint),
//   otherwise diffuse with its albedo; anything else: diffuse grey.

#include <prt/virtual_objects.h>

#include <rp_godot/godot.h>

#include <string>

namespace roomprobe {

// "" or why the instance cannot be drawn (no mesh, a surface that is not triangles, a shadow
// catcher whose transfer does not fit its mesh).
std::string virtual_object_from_instance(godot::MeshInstance3D *p_instance, VirtualObject *r_object);

} // namespace roomprobe
