#include "synth_renderer.h"

#include <io/embree_scene.h>
#include <math/hash.h>
#include <math/srgb.h>

#include <camera/omni_camera.h>
#include <camera/pinhole_camera.h>
#include <types/cubemap_layout.h>
#include <room/room_mesh.h>
#include <slam/slam_types.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace roomprobe::synth {

namespace {

constexpr double PI = std::numbers::pi;
constexpr double SHADOW_EPSILON = 1e-4; // metres

glm::dvec3 to_dvec3(const Vec3 &p_v) {
	return { p_v.x, p_v.y, p_v.z };
}

glm::dvec3 safe_normalize(const glm::dvec3 &p_v) {
	const double length = glm::length(p_v);
	return length > 0.0 ? p_v / length : glm::dvec3(0.0);
}

double uniform01(uint64_t p_hash) {
	return (static_cast<double>(p_hash >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// A standard normal value from a hash (Box-Muller).
double gaussian(uint64_t p_seed, uint64_t p_index) {
	const uint64_t h1 = splitmix64(p_seed ^ splitmix64(p_index * 2 + 1));
	const uint64_t h2 = splitmix64(h1 ^ 0x5851f42d4c957f2dULL);
	return std::sqrt(-2.0 * std::log(uniform01(h1))) * std::cos(2.0 * PI * uniform01(h2));
}

// A procedural sky for windows in scenes without a panorama.
Color procedural_sky(const glm::dvec3 &p_direction) {
	const glm::dvec3 d = safe_normalize(p_direction);
	if (d.y < 0.0) {
		return glm::mix(Color(0.25f, 0.3f, 0.15f), Color(0.1f, 0.12f, 0.06f), static_cast<float>(-d.y));
	}
	const float t = static_cast<float>(std::sqrt(d.y));
	Color sky = glm::mix(Color(1.2f, 1.3f, 1.4f), Color(0.35f, 0.55f, 1.1f), t);
	const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, 0.6, -0.75));
	if (glm::dot(d, sun) > 0.998) {
		sky += Color(30.0f, 28.0f, 24.0f);
	}
	return sky;
}

cv::Vec3f to_vec3f(const Color &p_c) {
	return cv::Vec3f(p_c.r, p_c.g, p_c.b);
}

glm::dmat3 rotation_matrix(const Pose &p_pose) {
	return glm::mat3_cast(p_pose.rotation);
}

// The thresholds between 8-bit sRGB codes, in linear values: code = number of thresholds below.
// A coarse table gives the code at the start of each 1/4096 step; a step holds at most two
// thresholds, so a short walk from there gives the exact code.
struct SrgbTable {
	static constexpr int STEPS = 4096;
	std::array<float, 255> thresholds;
	std::array<uint8_t, STEPS + 1> start;
	SrgbTable() {
		for (int k = 0; k < 255; ++k) {
			const double s = (k + 0.5) / 255.0;
			thresholds[k] = static_cast<float>(srgb_decode(s));
		}
		for (int i = 0; i <= STEPS; ++i) {
			const float v = static_cast<float>(i) / STEPS;
			start[i] = static_cast<uint8_t>(std::upper_bound(thresholds.begin(), thresholds.end(), v) - thresholds.begin());
		}
	}
	uint8_t code(float p_linear) const {
		if (!(p_linear > 0.0f)) {
			return 0;
		}
		if (p_linear >= 1.0f) {
			return 255;
		}
		int code = start[static_cast<int>(p_linear * STEPS)];
		while (code < 255 && p_linear > thresholds[code]) {
			++code;
		}
		return static_cast<uint8_t>(code);
	}
};

const SrgbTable &srgb_table() {
	static const SrgbTable table;
	return table;
}

} // namespace

// ---------------------------------------------------------------- Embree RAII

struct SynthRenderer::Embree : EmbreeTriangleScene {};

void SynthRenderer::add_triangle(const glm::dvec3 &p_a, const glm::dvec3 &p_b, const glm::dvec3 &p_c, const TriangleInfo &p_info) {
	const uint32_t base = static_cast<uint32_t>(vertices.size() / 3);
	for (const glm::dvec3 &v : { p_a, p_b, p_c }) {
		vertices.push_back(static_cast<float>(v.x));
		vertices.push_back(static_cast<float>(v.y));
		vertices.push_back(static_cast<float>(v.z));
	}
	indices.insert(indices.end(), { base, base + 1, base + 2 });
	triangles.push_back(p_info);
}

void SynthRenderer::add_quad(const Quad &p_quad) {
	TriangleInfo info;
	info.material = p_quad.material;
	info.origin = p_quad.corner;
	info.u_axis = safe_normalize(p_quad.edge_u);
	info.v_axis = safe_normalize(p_quad.edge_v);
	info.normal = safe_normalize(glm::cross(p_quad.edge_u, p_quad.edge_v));
	const glm::dvec3 a = p_quad.corner, b = a + p_quad.edge_u, c = b + p_quad.edge_v, d = a + p_quad.edge_v;
	add_triangle(a, b, c, info);
	add_triangle(a, c, d, info);
}

SynthRenderer::SynthRenderer(const Scene &p_scene) :
		scene_data(p_scene) {
	const int material_count = static_cast<int>(scene_data.materials.size());
	auto check_material = [&](int p_material, const std::string &p_what) {
		if (p_material < 0 || p_material >= material_count) {
			if (error_message.empty()) {
				error_message = p_what + ": material " + std::to_string(p_material) + " does not exist (the scene has " + std::to_string(material_count) + ")";
			}
			return false;
		}
		return true;
	};

	if (scene_data.has_room) {
		RoomMeshResult room = build_room_mesh(scene_data.room.floorplan);
		if (!room.ok) {
			error_message = "the room: " + room.error;
			return;
		}
		const RoomMesh &mesh = room.mesh;
		const size_t walls = mesh.floorplan.points.size();
		if (scene_data.room.wall_materials.size() != 1 && scene_data.room.wall_materials.size() != walls) {
			error_message = "the room has " + std::to_string(walls) + " walls but " + std::to_string(scene_data.room.wall_materials.size()) + " wall materials";
			return;
		}
		for (size_t t = 0; t < mesh.triangle_charts.size(); ++t) {
			const Chart &chart = mesh.charts[mesh.triangle_charts[t]];
			TriangleInfo info;
			switch (chart.kind) {
				case SurfaceKind::Wall:
					info.material = scene_data.room.wall_materials.size() == 1 ? scene_data.room.wall_materials[0] : scene_data.room.wall_materials[chart.wall_index];
					break;
				case SurfaceKind::Floor:
					info.material = scene_data.room.floor_material;
					break;
				case SurfaceKind::Ceiling:
					info.material = scene_data.room.ceiling_material;
					break;
			}
			if (!check_material(info.material, "the room")) {
				return;
			}
			info.origin = to_dvec3(chart.origin_m);
			info.u_axis = safe_normalize(to_dvec3(chart.u_axis_m));
			info.v_axis = safe_normalize(to_dvec3(chart.v_axis_m));
			info.normal = safe_normalize(to_dvec3(chart.normal));
			auto vertex = [&](uint32_t p_index) {
				const Vec3f &p = mesh.positions[p_index];
				return glm::dvec3(p.x, p.y, p.z);
			};
			add_triangle(vertex(mesh.indices[3 * t]), vertex(mesh.indices[3 * t + 1]), vertex(mesh.indices[3 * t + 2]), info);
		}
	}
	for (size_t i = 0; i < scene_data.quads.size(); ++i) {
		if (!check_material(scene_data.quads[i].material, "quad " + std::to_string(i))) {
			return;
		}
		add_quad(scene_data.quads[i]);
	}
	for (size_t i = 0; i < scene_data.boxes.size(); ++i) {
		const Box &box = scene_data.boxes[i];
		const int top = box.top_material >= 0 ? box.top_material : box.material;
		if (!check_material(box.material, "box " + std::to_string(i)) || !check_material(top, "box " + std::to_string(i))) {
			return;
		}
		const double c = std::cos(box.yaw_rad), s = std::sin(box.yaw_rad);
		// Local axes turned about Y.
		const glm::dvec3 ax(c, 0.0, -s), ay(0.0, 1.0, 0.0), az(s, 0.0, c);
		const glm::dvec3 hx = ax * box.half_size.x, hy = ay * box.half_size.y, hz = az * box.half_size.z;
		const glm::dvec3 o = box.center;
		// Sides: textured with u along the face and v downwards; top and bottom: u = x, v = z.
		const Quad faces[6] = {
			{ o + hx + hy - hz, 2.0 * hz, -2.0 * hy, box.material }, // +x
			{ o - hx + hy + hz, -2.0 * hz, -2.0 * hy, box.material }, // -x
			{ o - hx + hy + hz, 2.0 * hx, -2.0 * hy, box.material }, // +z
			{ o + hx + hy - hz, -2.0 * hx, -2.0 * hy, box.material }, // -z
			{ o - hx + hy - hz, 2.0 * hx, 2.0 * hz, top }, // +y
			{ o - hx - hy - hz, 2.0 * hx, 2.0 * hz, box.material }, // -y
		};
		for (const Quad &face : faces) {
			add_quad(face);
		}
	}
	for (size_t i = 0; i < scene_data.spheres.size(); ++i) {
		const Sphere &sphere = scene_data.spheres[i];
		if (!check_material(sphere.material, "sphere " + std::to_string(i))) {
			return;
		}
		// Tessellated finely; shading uses the true sphere (normal, point, coordinates).
		constexpr int SLICES = 64, STACKS = 32;
		TriangleInfo info;
		info.material = sphere.material;
		info.sphere = static_cast<int>(i);
		auto point = [&](int p_slice, int p_stack) {
			const double phi = 2.0 * PI * p_slice / SLICES, theta = PI * p_stack / STACKS;
			return sphere.center + sphere.radius * glm::dvec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
		};
		for (int st = 0; st < STACKS; ++st) {
			for (int sl = 0; sl < SLICES; ++sl) {
				const glm::dvec3 a = point(sl, st), b = point(sl + 1, st), c = point(sl + 1, st + 1), d = point(sl, st + 1);
				if (st > 0) {
					add_triangle(a, b, c, info);
				}
				if (st < STACKS - 1) {
					add_triangle(a, c, d, info);
				}
			}
		}
	}
	if (triangles.empty()) {
		error_message = "the scene has no geometry";
		return;
	}
	for (size_t i = 0; i < scene_data.lights.size(); ++i) {
		const Light &light = scene_data.lights[i];
		if (light.kind == LightKind::Point) {
			light_samples.push_back({ static_cast<int>(i), light.position, 1.0 });
			continue;
		}
		const int nu = std::max(1, light.samples_u), nv = std::max(1, light.samples_v);
		const double area = glm::length(glm::cross(light.edge_u, light.edge_v));
		for (int v = 0; v < nv; ++v) {
			for (int u = 0; u < nu; ++u) {
				const glm::dvec3 p = light.position + light.edge_u * ((u + 0.5) / nu) + light.edge_v * ((v + 0.5) / nv);
				light_samples.push_back({ static_cast<int>(i), p, area / (nu * nv) });
			}
		}
	}

	embree = std::make_unique<Embree>();
	error_message = embree->build(vertices, indices, true);
}

SynthRenderer::~SynthRenderer() = default;

Hit SynthRenderer::intersect(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) const {
	Hit hit;
	if (!embree || !embree->built()) {
		return hit;
	}
	EmbreeTriangleScene::RayHit rh;
	if (!embree->intersect(p_origin, p_direction, p_t_near, p_t_far, &rh)) {
		return hit;
	}
	const TriangleInfo &info = triangles[rh.triangle];
	hit.hit = true;
	hit.distance = rh.t;
	hit.point = p_origin + hit.distance * p_direction;
	hit.material = info.material;
	if (info.sphere >= 0) {
		const Sphere &sphere = scene_data.spheres[info.sphere];
		const glm::dvec3 n = safe_normalize(hit.point - sphere.center);
		hit.point = sphere.center + sphere.radius * n;
		hit.normal = n;
		hit.u_m = (std::atan2(n.z, n.x) + PI) * sphere.radius;
		hit.v_m = std::acos(std::clamp(n.y, -1.0, 1.0)) * sphere.radius;
	} else {
		hit.normal = info.normal;
		const glm::dvec3 d = hit.point - info.origin;
		hit.u_m = glm::dot(d, info.u_axis);
		hit.v_m = glm::dot(d, info.v_axis);
	}
	if (glm::dot(hit.normal, p_direction) > 0.0) {
		hit.normal = -hit.normal;
	}
	return hit;
}

bool SynthRenderer::occluded(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) const {
	if (!embree || !embree->built() || !(p_t_far > p_t_near)) {
		return false;
	}
	return embree->occluded(p_origin, p_direction, p_t_near, p_t_far);
}

Color SynthRenderer::emission(const Material &p_material, const Hit &p_hit, const glm::dvec3 &p_direction, double p_time_s) const {
	if (p_material.emission == Emission::None || !is_on(p_material.on_from_s, p_material.on_until_s, p_time_s)) {
		return Color(0.0f);
	}
	switch (p_material.emission) {
		case Emission::None:
			break;
		case Emission::Constant:
			return p_material.emission_scale;
		case Emission::Panorama:
			return p_material.emission_scale * (scene_data.panorama ? scene_data.panorama->lookup(p_direction) : procedural_sky(p_direction));
		case Emission::ProjectedPanorama: {
			const glm::dvec3 from_center = p_hit.point - scene_data.panorama_center;
			return p_material.emission_scale * (scene_data.panorama ? scene_data.panorama->lookup(from_center) : procedural_sky(from_center));
		}
		case Emission::Screen: {
			const double x = p_hit.u_m / std::max(1e-9, p_material.screen_width_m);
			const double y = p_hit.v_m / std::max(1e-9, p_material.screen_height_m);
			return p_material.emission_scale * screen_content(std::clamp(x, 0.0, 1.0), std::clamp(y, 0.0, 1.0), p_time_s);
		}
	}
	return Color(0.0f);
}

Color SynthRenderer::shade(const Hit &p_hit, const glm::dvec3 &p_direction, double p_time_s) const {
	if (!p_hit.hit) {
		return scene_data.background;
	}
	const Material &material = scene_data.materials[p_hit.material];
	const Color emitted = emission(material, p_hit, p_direction, p_time_s);
	const Color albedo = evaluate_texture(material.albedo, p_hit.u_m, p_hit.v_m);
	if (material.unlit || !lighting_enabled) {
		return emitted + albedo;
	}
	if (albedo.r <= 0.0f && albedo.g <= 0.0f && albedo.b <= 0.0f) {
		return emitted;
	}
	glm::dvec3 irradiance(scene_data.ambient);
	for (const Light &light : scene_data.lights) {
		if (is_on(light.on_from_s, light.on_until_s, p_time_s)) {
			irradiance += glm::dvec3(light.ambient);
		}
	}
	const glm::dvec3 origin = p_hit.point + p_hit.normal * SHADOW_EPSILON;
	glm::dvec3 direct(0.0);
	for (const LightSample &sample : light_samples) {
		const Light &light = scene_data.lights[sample.light];
		if (!is_on(light.on_from_s, light.on_until_s, p_time_s)) {
			continue;
		}
		const glm::dvec3 to_light = sample.position - origin;
		const double distance2 = std::max(glm::dot(to_light, to_light), 1e-4);
		const double distance = std::sqrt(distance2);
		const glm::dvec3 l = to_light / distance;
		const double cos_surface = glm::dot(p_hit.normal, l);
		if (cos_surface <= 0.0) {
			continue;
		}
		double geometry = cos_surface / distance2;
		if (light.kind == LightKind::Rect) {
			const double cos_light = -glm::dot(safe_normalize(glm::cross(light.edge_u, light.edge_v)), l);
			if (cos_light <= 0.0) {
				continue;
			}
			geometry *= cos_light * sample.weight;
		}
		if (occluded(origin, l, 0.0, distance - light.shadow_skip_m - SHADOW_EPSILON)) {
			continue;
		}
		direct += glm::dvec3(light.power) * geometry;
	}
	irradiance += direct / PI;
	return emitted + albedo * Color(irradiance);
}

Color SynthRenderer::radiance(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_time_s, Hit *r_hit) const {
	const Hit hit = intersect(p_origin, p_direction);
	if (r_hit) {
		*r_hit = hit;
	}
	return shade(hit, p_direction, p_time_s);
}

// ---------------------------------------------------------------- tone mapping

uint8_t linear_to_srgb8(float p_linear) {
	return srgb_table().code(p_linear);
}

float srgb8_to_linear(uint8_t p_code) {
	return static_cast<float>(srgb_decode(p_code / 255.0));
}

cv::Mat to_srgb8(const cv::Mat &p_linear, double p_exposure) {
	CV_Assert(p_linear.type() == CV_32FC3);
	cv::Mat out(p_linear.size(), CV_8UC3);
	const float exposure = static_cast<float>(p_exposure);
	const SrgbTable &table = srgb_table();
	for (int y = 0; y < p_linear.rows; ++y) {
		const cv::Vec3f *in = p_linear.ptr<cv::Vec3f>(y);
		cv::Vec3b *o = out.ptr<cv::Vec3b>(y);
		for (int x = 0; x < p_linear.cols; ++x) {
			for (int c = 0; c < 3; ++c) {
				o[x][c] = table.code(in[x][c] * exposure);
			}
		}
	}
	return out;
}

cv::Mat encode_8bit(const cv::Mat &p_linear, ToneCurve p_curve, const glm::dvec3 &p_channel_gains) {
	CV_Assert(p_linear.type() == CV_32FC3);
	if (p_curve == ToneCurve::Srgb && p_channel_gains == glm::dvec3(1.0)) {
		return to_srgb8(p_linear, 1.0);
	}
	cv::Mat out(p_linear.size(), CV_8UC3);
	const float gains[3] = { float(p_channel_gains.x), float(p_channel_gains.y), float(p_channel_gains.z) };
	tbb::parallel_for(0, p_linear.rows, [&](int y) {
		const cv::Vec3f *in = p_linear.ptr<cv::Vec3f>(y);
		cv::Vec3b *o = out.ptr<cv::Vec3b>(y);
		for (int x = 0; x < p_linear.cols; ++x) {
			for (int c = 0; c < 3; ++c) {
				o[x][c] = encode_tone(p_curve, in[x][c] * gains[c]);
			}
		}
	});
	return out;
}

// ---------------------------------------------------------------- RGB-D

double kinect_depth_sigma_m(double p_z_m) {
	return DepthNoiseModel().sigma_m(p_z_m); // the model the tracker weighs readings by
}

uint64_t mix_seed(uint64_t p_a, uint64_t p_b) {
	return splitmix64(splitmix64(p_a) ^ (p_b + 0x632be59bd9b4e019ULL));
}

RgbdImage render_rgbd(const SynthRenderer &p_renderer, const PinholeParams &p_camera, double p_depth_scale_m,
		const Pose &p_world_from_camera, double p_time_s, const RgbdOptions &p_options) {
	const int width = p_camera.width, height = p_camera.height;
	RgbdImage image;
	image.radiance = cv::Mat(height, width, CV_32FC3, cv::Scalar::all(0));
	image.depth_true_m = cv::Mat(height, width, CV_32FC1, cv::Scalar::all(0));
	image.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar::all(0));
	cv::Mat valid(height, width, CV_8UC1, cv::Scalar::all(0)); // a reading before edges and noise
	const glm::dmat3 rotation = rotation_matrix(p_world_from_camera);
	const glm::dvec3 origin = p_world_from_camera.translation;
	const glm::dvec3 projector = transform_point(p_world_from_camera, glm::dvec3(p_options.projector_baseline_m, 0.0, 0.0));
	const double cos_grazing = std::cos(p_options.grazing_angle_deg * PI / 180.0);
	const int n = std::max(1, p_options.samples_per_axis);

	tbb::parallel_for(0, height, [&](int y) {
		cv::Vec3f *radiance_row = image.radiance.ptr<cv::Vec3f>(y);
		float *depth_row = image.depth_true_m.ptr<float>(y);
		uint8_t *valid_row = valid.ptr<uint8_t>(y);
		for (int x = 0; x < width; ++x) {
			// The centre ray: colour (n = 1) and depth. Direction (x', y', 1) in the camera frame,
			// so the hit distance is z.
			const glm::dvec3 ray_camera = unproject_pinhole(p_camera, glm::dvec2(x, y));
			const glm::dvec3 direction = rotation * ray_camera;
			Hit hit;
			Color colour = p_renderer.radiance(origin, direction, p_time_s, &hit);
			if (n > 1) {
				colour = Color(0.0f);
				for (int sy = 0; sy < n; ++sy) {
					for (int sx = 0; sx < n; ++sx) {
						const glm::dvec2 pixel(x - 0.5 + (sx + 0.5) / n, y - 0.5 + (sy + 0.5) / n);
						colour += p_renderer.radiance(origin, rotation * unproject_pinhole(p_camera, pixel), p_time_s);
					}
				}
				colour /= static_cast<float>(n * n);
			}
			radiance_row[x] = to_vec3f(colour);
			if (!hit.hit) {
				continue;
			}
			const double z = hit.distance;
			depth_row[x] = static_cast<float>(z);
			if (z < p_options.min_depth_m || z > p_options.max_depth_m) {
				continue;
			}
			const double cos_angle = std::abs(glm::dot(hit.normal, glm::normalize(direction)));
			if (cos_angle < cos_grazing) {
				continue;
			}
			if (p_options.projector_baseline_m != 0.0) {
				const glm::dvec3 from = hit.point + hit.normal * SHADOW_EPSILON;
				const glm::dvec3 to_projector = projector - from;
				const double distance = glm::length(to_projector);
				if (glm::dot(to_projector, hit.normal) <= 0.0 || p_renderer.occluded(from, to_projector / distance, 0.0, distance - SHADOW_EPSILON)) {
					continue;
				}
			}
			valid_row[x] = 1;
		}
	});

	const uint64_t seed = p_options.noise_seed;
	const double scale = p_depth_scale_m > 0.0 ? p_depth_scale_m : 0.001;
	tbb::parallel_for(0, height, [&](int y) {
		const float *depth_row = image.depth_true_m.ptr<float>(y);
		const uint8_t *valid_row = valid.ptr<uint8_t>(y);
		uint16_t *out = image.depth.ptr<uint16_t>(y);
		for (int x = 0; x < width; ++x) {
			if (!valid_row[x]) {
				continue;
			}
			const double z = depth_row[x];
			const double jump = std::max(p_options.edge_jump_m, p_options.edge_jump_relative * z);
			bool edge = false;
			for (int dy = -1; dy <= 1 && !edge; ++dy) {
				const int yy = y + dy;
				if (yy < 0 || yy >= height) {
					continue;
				}
				const float *row = image.depth_true_m.ptr<float>(yy);
				for (int dx = -1; dx <= 1; ++dx) {
					const int xx = x + dx;
					if (xx < 0 || xx >= width || (dx == 0 && dy == 0)) {
						continue;
					}
					if (row[xx] > 0.0f && z - row[xx] > jump) {
						edge = true;
						break;
					}
				}
			}
			if (edge) {
				continue;
			}
			double measured = z;
			if (p_options.depth_noise) {
				measured += kinect_depth_sigma_m(z) * gaussian(seed, static_cast<uint64_t>(y) * width + x);
			}
			const double units = std::round(measured / scale);
			out[x] = static_cast<uint16_t>(std::clamp(units, 1.0, 65535.0));
		}
	});
	image.rgb = to_srgb8(image.radiance, p_options.exposure);
	return image;
}

// ---------------------------------------------------------------- fisheye

FisheyeImage render_fisheye(const SynthRenderer &p_renderer, const OmniParams &p_camera, const Pose &p_world_from_camera,
		double p_time_s, const FisheyeOptions &p_options) {
	const int width = p_camera.width, height = p_camera.height;
	FisheyeImage image;
	image.radiance = cv::Mat(height, width, CV_32FC3, cv::Scalar::all(0));
	const glm::dmat3 rotation = rotation_matrix(p_world_from_camera);
	const glm::dvec3 origin = p_world_from_camera.translation;
	const int n = std::max(1, p_options.samples_per_axis);
	const float exposure = static_cast<float>(p_options.exposure);
	tbb::parallel_for(0, height, [&](int y) {
		cv::Vec3f *row = image.radiance.ptr<cv::Vec3f>(y);
		for (int x = 0; x < width; ++x) {
			Color sum(0.0f);
			for (int sy = 0; sy < n; ++sy) {
				for (int sx = 0; sx < n; ++sx) {
					const glm::dvec2 pixel = n == 1 ? glm::dvec2(x, y) : glm::dvec2(x - 0.5 + (sx + 0.5) / n, y - 0.5 + (sy + 0.5) / n);
					glm::dvec3 ray;
					if (!omni_pixel_valid(p_camera, pixel) || !unproject_omni(p_camera, pixel, &ray)) {
						continue;
					}
					const float gain = static_cast<float>(fisheye_vignetting(p_camera, pixel, p_options.vignetting_edge_gain));
					sum += gain * p_renderer.radiance(origin, rotation * ray, p_time_s);
				}
			}
			row[x] = to_vec3f(sum * (exposure / static_cast<float>(n * n)));
		}
	});
	image.image = encode_8bit(image.radiance, p_options.tone_curve, p_options.channel_gains);
	return image;
}

// ---------------------------------------------------------------- cubemaps

std::array<cv::Mat, 6> render_cubemap(const SynthRenderer &p_renderer, const glm::dvec3 &p_position, double p_time_s, int p_size) {
	std::array<cv::Mat, 6> faces;
	for (cv::Mat &face : faces) {
		face = cv::Mat(p_size, p_size, CV_32FC3, cv::Scalar::all(0));
	}
	tbb::parallel_for(0, 6 * p_size, [&](int p_row) {
		const int face = p_row / p_size, y = p_row % p_size;
		cv::Vec3f *row = faces[face].ptr<cv::Vec3f>(y);
		for (int x = 0; x < p_size; ++x) {
			row[x] = to_vec3f(p_renderer.radiance(p_position, cubemap_direction(face, x, y, p_size), p_time_s));
		}
	});
	return faces;
}

} // namespace roomprobe::synth
