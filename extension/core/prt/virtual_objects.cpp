#include "virtual_objects.h"

#include "contact_shadow.h"

#include <glm/geometric.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace roomprobe {

namespace {

// One Embree scene of the objects p_take selects; per triangle, its object and its triangle in
// that object's mesh.
std::string build_scene(const std::vector<VirtualObject> &p_objects, bool p_catchers, EmbreeTriangleScene *r_scene, std::vector<uint32_t> *r_object,
		std::vector<uint32_t> *r_triangle) {
	std::vector<float> xyz;
	std::vector<uint32_t> indices;
	for (size_t o = 0; o < p_objects.size(); o++) {
		const VirtualObject &object = p_objects[o];
		if ((object.look == VirtualLook::ShadowCatcher) != p_catchers) {
			continue;
		}
		const uint32_t base = uint32_t(xyz.size() / 3);
		for (const glm::vec3 &p : object.mesh.positions) {
			xyz.insert(xyz.end(), { p.x, p.y, p.z });
		}
		for (size_t t = 0; t < object.mesh.triangle_count(); t++) {
			for (int k = 0; k < 3; k++) {
				indices.push_back(base + object.mesh.indices[3 * t + size_t(k)]);
			}
			r_object->push_back(uint32_t(o));
			r_triangle->push_back(uint32_t(t));
		}
	}
	if (indices.empty()) {
		return "";
	}
	return r_scene->build(xyz, indices, false);
}

glm::dvec3 interpolated_normal(const PrtMesh &p_mesh, uint32_t p_triangle, float p_u, float p_v) {
	const uint32_t *tri = &p_mesh.indices[3 * size_t(p_triangle)];
	const glm::dvec3 n = (1.0 - p_u - p_v) * glm::dvec3(p_mesh.normals[tri[0]]) + double(p_u) * glm::dvec3(p_mesh.normals[tri[1]]) +
			double(p_v) * glm::dvec3(p_mesh.normals[tri[2]]);
	const double length = glm::length(n);
	return length > 1e-12 ? n / length : glm::dvec3(0.0, 1.0, 0.0);
}

} // namespace

std::string VirtualScene::make(std::vector<VirtualObject> p_objects, std::shared_ptr<const VirtualScene> *r_scene) {
	for (size_t o = 0; o < p_objects.size(); o++) {
		VirtualObject &object = p_objects[o];
		const std::string problem = check_prt_mesh(object.mesh);
		if (!problem.empty()) {
			return "virtual object " + std::to_string(o) + ": " + problem;
		}
		if (object.look == VirtualLook::ShadowCatcher && object.transfer.size() != object.mesh.vertex_count()) {
			return "virtual object " + std::to_string(o) + ": a shadow catcher needs one transfer vector per vertex (" +
					std::to_string(object.transfer.size()) + " for " + std::to_string(object.mesh.vertex_count()) + " vertices)";
		}
		if (!std::isfinite(object.color.x + object.color.y + object.color.z) || !std::isfinite(object.ior) || object.ior < 1.0) {
			return "virtual object " + std::to_string(o) + ": its colour must be finite and its ior at least 1";
		}
	}
	std::shared_ptr<VirtualScene> scene(new VirtualScene());
	scene->objects = std::move(p_objects);
	std::string error = build_scene(scene->objects, false, &scene->solids, &scene->solid_object, &scene->solid_triangle);
	if (error.empty()) {
		error = build_scene(scene->objects, true, &scene->catchers, &scene->catcher_object, &scene->catcher_triangle);
	}
	if (!error.empty()) {
		return "virtual objects: " + error;
	}
	// A bounding sphere of everything (the box's): texels outside its cone are not traced.
	glm::dvec3 lo(1e300), hi(-1e300);
	for (const VirtualObject &object : scene->objects) {
		for (const glm::vec3 &p : object.mesh.positions) {
			lo = glm::min(lo, glm::dvec3(p));
			hi = glm::max(hi, glm::dvec3(p));
		}
	}
	if (!scene->objects.empty()) {
		scene->bound_centre = 0.5 * (lo + hi);
		scene->bound_radius = 0.5 * glm::length(hi - lo);
	}
	*r_scene = scene;
	return "";
}

VirtualDrawStats VirtualScene::draw(const glm::dvec3 &p_position_m, const ShCoefficients &p_light, const Cubemap *p_previous, Cubemap *io_map) const {
	VirtualDrawStats stats;
	const auto start = std::chrono::steady_clock::now();
	if (objects.empty() || io_map == nullptr || !is_valid_cubemap(*io_map)) {
		return stats;
	}
	const ShCoefficients irradiance = convolve_cosine_lobe(p_light);
	const bool have_previous = p_previous != nullptr && is_valid_cubemap(*p_previous);
	// Per catcher: the contact-shadow ratio at each vertex under this light (prt/contact_shadow.h),
	// the light turned into the transfer's frame.
	std::vector<std::vector<float>> ratios(objects.size());
	for (size_t o = 0; o < objects.size(); o++) {
		const VirtualObject &object = objects[o];
		if (object.look != VirtualLook::ShadowCatcher) {
			continue;
		}
		const ShCoefficients local = rotate_sh(p_light, object.transfer_frame);
		const glm::dvec3 local_normal = glm::transpose(object.transfer_frame) * object.plane_normal;
		ratios[o].resize(object.transfer.size());
		for (size_t v = 0; v < object.transfer.size(); v++) {
			ratios[o][v] = float(shadow_ratio(object.transfer[v], local_normal, local));
		}
	}
	// The cone of the bounding sphere; inside it, every direction.
	const glm::dvec3 to_centre = bound_centre - p_position_m;
	const double distance = glm::length(to_centre);
	const bool inside = distance <= bound_radius;
	const glm::dvec3 axis = inside ? glm::dvec3(0.0) : to_centre / distance;
	const double cos_cone = inside ? -1.0 : std::sqrt(std::max(0.0, 1.0 - (bound_radius / distance) * (bound_radius / distance)));
	const int n = io_map->size;
	std::vector<VirtualDrawStats> per_row(size_t(6 * n));
	tbb::parallel_for(0, 6 * n, [&](int p_row) {
		const int face = p_row / n, y = p_row % n;
		cv::Vec3f *row = io_map->faces[size_t(face)].ptr<cv::Vec3f>(y);
		VirtualDrawStats &s = per_row[size_t(p_row)];
		for (int x = 0; x < n; x++) {
			const glm::dvec3 d = cubemap_direction(face, x, y, n);
			if (!inside && glm::dot(d, axis) < cos_cone) {
				continue;
			}
			s.texels_traced++;
			EmbreeTriangleScene::RayHit solid, catcher;
			const bool hit_solid = solids.intersect(p_position_m, d, 0.0, 1e30, &solid);
			const bool hit_catcher = catchers.intersect(p_position_m, d, 0.0, hit_solid ? double(solid.t) : 1e30, &catcher);
			if (hit_catcher) {
				const uint32_t o = catcher_object[catcher.triangle];
				const uint32_t *tri = &objects[o].mesh.indices[3 * size_t(catcher_triangle[catcher.triangle])];
				const std::vector<float> &r = ratios[o];
				const float ratio = (1.0f - catcher.u - catcher.v) * r[tri[0]] + catcher.u * r[tri[1]] + catcher.v * r[tri[2]];
				row[x] *= ratio;
				s.texels_shadowed++;
				continue;
			}
			if (!hit_solid) {
				continue;
			}
			const VirtualObject &object = objects[solid_object[solid.triangle]];
			glm::dvec3 normal = interpolated_normal(object.mesh, solid_triangle[solid.triangle], solid.u, solid.v);
			if (glm::dot(normal, d) > 0.0) {
				normal = -normal; // seen from inside, or a back face
			}
			glm::dvec3 color(0.0);
			const bool from_map = have_previous && object.look != VirtualLook::Diffuse;
			if (!from_map) {
				color = object.color * glm::max(evaluate_sh(irradiance, normal), glm::dvec3(0.0)) / std::numbers::pi;
			} else {
				const glm::dvec3 reflected = glm::reflect(d, normal);
				color = sample_cubemap(*p_previous, reflected);
				if (object.look == VirtualLook::Glass) {
					const double f0 = std::pow((object.ior - 1.0) / (object.ior + 1.0), 2.0);
					const double fresnel = f0 + (1.0 - f0) * std::pow(1.0 - std::clamp(-glm::dot(d, normal), 0.0, 1.0), 5.0);
					const glm::dvec3 through = glm::refract(d, normal, 1.0 / object.ior);
					const glm::dvec3 behind = glm::length(through) > 0.0 ? sample_cubemap(*p_previous, through) : color;
					color = fresnel * color + (1.0 - fresnel) * behind;
				}
				color *= object.color;
			}
			row[x] = cv::Vec3f(float(color.x), float(color.y), float(color.z));
			s.texels_drawn++;
		}
	});
	for (const VirtualDrawStats &s : per_row) {
		stats.texels_traced += s.texels_traced;
		stats.texels_drawn += s.texels_drawn;
		stats.texels_shadowed += s.texels_shadowed;
	}
	stats.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	return stats;
}

} // namespace roomprobe
