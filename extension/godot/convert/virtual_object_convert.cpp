#include "virtual_object_convert.h"

#include "mesh_convert.h"
#include "pose_convert.h"
#include "../resources/prt_transfer.h"

#include <math/srgb.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

using namespace godot;

namespace roomprobe {

namespace {

glm::dvec3 linear_from_srgb(const Color &p_color) {
	return glm::dvec3(srgb_decode(p_color.r), srgb_decode(p_color.g), srgb_decode(p_color.b));
}

// A vec3 uniform (RoomProbe's shaders' tint), or p_default when the material does not set it.
glm::dvec3 vector_parameter(const Ref<ShaderMaterial> &p_material, const char *p_name, const glm::dvec3 &p_default) {
	const Variant value = p_material->get_shader_parameter(p_name);
	if (value.get_type() == Variant::VECTOR3) {
		return to_glm(Vector3(value));
	}
	if (value.get_type() == Variant::COLOR) {
		const Color c = value;
		return glm::dvec3(c.r, c.g, c.b);
	}
	return p_default;
}

bool shader_is(const Ref<ShaderMaterial> &p_material, const char *p_file) {
	const Ref<Shader> shader = p_material->get_shader();
	return shader.is_valid() && shader->get_path().ends_with(p_file);
}

std::string read_look(const Ref<Material> &p_material, const Transform3D &p_transform, VirtualObject *r_object) {
	r_object->look = VirtualLook::Diffuse;
	r_object->color = glm::dvec3(0.5);
	const Ref<ShaderMaterial> shader_material = p_material;
	if (shader_material.is_valid()) {
		if (shader_is(shader_material, "/mirror.gdshader") || shader_is(shader_material, "/rough_metal.gdshader")) {
			r_object->look = VirtualLook::Mirror;
			r_object->color = vector_parameter(shader_material, "tint", glm::dvec3(1.0));
		} else if (shader_is(shader_material, "/glass.gdshader")) {
			r_object->look = VirtualLook::Glass;
			r_object->color = vector_parameter(shader_material, "tint", glm::dvec3(1.0));
			const Variant ior = shader_material->get_shader_parameter("ior");
			r_object->ior = ior.get_type() == Variant::FLOAT ? double(ior) : 1.5;
		} else if (shader_is(shader_material, "/contact_shadow.gdshader")) {
			r_object->look = VirtualLook::ShadowCatcher;
			const Variant texture = shader_material->get_shader_parameter("transfer");
			const Ref<Texture2D> transfer = Ref<Texture2D>(cast_to<Texture2D>(texture.get_object()));
			if (transfer.is_null()) {
				return "its contact_shadow material has no transfer texture";
			}
			const std::string error = PRTTransfer::transfer_from_image(transfer->get_image(), int(r_object->mesh.vertex_count()), &r_object->transfer);
			if (!error.empty()) {
				return "its contact_shadow transfer: " + error;
			}
			glm::dmat3 frame;
			if (!rotation_from_basis(p_transform.basis, &frame)) {
				return "its transform is degenerate";
			}
			r_object->transfer_frame = frame;
			const glm::dvec3 normal = vector_parameter(shader_material, "plane_normal", glm::dvec3(0.0, 1.0, 0.0));
			r_object->plane_normal = glm::length(normal) > 0.0 ? glm::normalize(normal) : glm::dvec3(0.0, 1.0, 0.0);
		} else if (shader_is(shader_material, "/prt_diffuse.gdshader") || shader_is(shader_material, "/sh_diffuse.gdshader")) {
			const Variant albedo = shader_material->get_shader_parameter("albedo");
			if (albedo.get_type() == Variant::COLOR) {
				r_object->color = linear_from_srgb(Color(albedo));
			} else if (albedo.get_type() == Variant::VECTOR3) {
				const Vector3 a = albedo;
				r_object->color = linear_from_srgb(Color(a.x, a.y, a.z));
			} else {
				r_object->color = linear_from_srgb(Color(0.8f, 0.8f, 0.8f));
			}
		}
		return "";
	}
	const Ref<BaseMaterial3D> standard = p_material;
	if (standard.is_valid()) {
		r_object->color = linear_from_srgb(standard->get_albedo());
		if (standard->get_metallic() >= 0.5f && standard->get_roughness() < 0.35f) {
			r_object->look = VirtualLook::Mirror;
		}
	}
	return "";
}

} // namespace

std::string virtual_object_from_instance(MeshInstance3D *p_instance, VirtualObject *r_object) {
	*r_object = VirtualObject();
	const Ref<Mesh> mesh = p_instance->get_mesh();
	if (mesh.is_null() || mesh->get_surface_count() < 1) {
		return "it has no mesh";
	}
	// Every surface, in one mesh (its first material gives the look).
	for (int s = 0; s < mesh->get_surface_count(); s++) {
		PrtMesh surface;
		const std::string error = prt_mesh_from_surface(mesh, s, &surface);
		if (!error.empty()) {
			return error;
		}
		const uint32_t base = uint32_t(r_object->mesh.positions.size());
		r_object->mesh.positions.insert(r_object->mesh.positions.end(), surface.positions.begin(), surface.positions.end());
		r_object->mesh.normals.insert(r_object->mesh.normals.end(), surface.normals.begin(), surface.normals.end());
		for (uint32_t i : surface.indices) {
			r_object->mesh.indices.push_back(base + i);
		}
	}
	// Into the world: positions by the transform, normals by its inverse transpose.
	const Transform3D transform = p_instance->get_global_transform();
	const glm::dmat3 linear = to_glm(transform.basis);
	if (!(std::abs(glm::determinant(linear)) > 1e-12)) {
		return "its transform is degenerate";
	}
	const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
	const glm::dvec3 origin = to_glm(transform.origin);
	for (size_t v = 0; v < r_object->mesh.positions.size(); v++) {
		r_object->mesh.positions[v] = glm::vec3(linear * glm::dvec3(r_object->mesh.positions[v]) + origin);
		r_object->mesh.normals[v] = glm::vec3(glm::normalize(normal_matrix * glm::dvec3(r_object->mesh.normals[v])));
	}
	Ref<Material> material = p_instance->get_material_override();
	if (material.is_null()) {
		material = p_instance->get_active_material(0);
	}
	return read_look(material, transform, r_object);
}

} // namespace roomprobe
