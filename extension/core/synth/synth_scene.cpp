#include <io/opencv.h>

#include "synth_scene.h"

#include <io/image_codec.h>
#include <io/input_path.h>
#include <io/radiance_hdr.h>
#include <recording/recording_io.h>
#include <room/reference_rooms.h>


#include <glm/geometric.hpp>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <fstream>
#include <numbers>

namespace roomprobe::synth {

namespace {

constexpr double PI = std::numbers::pi;

uint32_t hash_u32(uint32_t p_x) {
	// lowbias32 (Chris Wellons): a good 32-bit integer finaliser.
	p_x ^= p_x >> 16;
	p_x *= 0x7feb352dU;
	p_x ^= p_x >> 15;
	p_x *= 0x846ca68bU;
	p_x ^= p_x >> 16;
	return p_x;
}

// A hashed value in [0, 1) for an integer lattice point.
float hash01(int64_t p_x, int64_t p_y, uint32_t p_seed) {
	uint32_t h = hash_u32(p_seed ^ 0x9e3779b9U);
	h = hash_u32(h ^ static_cast<uint32_t>(p_x));
	h = hash_u32(h ^ static_cast<uint32_t>(p_y) * 0x85ebca6bU);
	return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

double smooth(double p_t) {
	return p_t * p_t * (3.0 - 2.0 * p_t);
}

// Value noise in [0, 1) with unit feature size.
double value_noise(double p_x, double p_y, uint32_t p_seed) {
	const double fx = std::floor(p_x), fy = std::floor(p_y);
	const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
	const double tx = smooth(p_x - fx), ty = smooth(p_y - fy);
	const double v00 = hash01(ix, iy, p_seed), v10 = hash01(ix + 1, iy, p_seed);
	const double v01 = hash01(ix, iy + 1, p_seed), v11 = hash01(ix + 1, iy + 1, p_seed);
	return (v00 * (1.0 - tx) + v10 * tx) * (1.0 - ty) + (v01 * (1.0 - tx) + v11 * tx) * ty;
}

Color mix(const Color &p_a, const Color &p_b, double p_t) {
	const float t = static_cast<float>(p_t);
	return p_a * (1.0f - t) + p_b * t;
}

int64_t floor_i(double p_x) {
	return static_cast<int64_t>(std::floor(p_x));
}

Color hsv(double p_h, double p_s, double p_v) {
	const double h = (p_h - std::floor(p_h)) * 6.0;
	const int i = static_cast<int>(h) % 6;
	const double f = h - std::floor(h);
	const double p = p_v * (1.0 - p_s), q = p_v * (1.0 - p_s * f), t = p_v * (1.0 - p_s * (1.0 - f));
	switch (i) {
		case 0: return Color(p_v, t, p);
		case 1: return Color(q, p_v, p);
		case 2: return Color(p, p_v, t);
		case 3: return Color(p, q, p_v);
		case 4: return Color(t, p, p_v);
		default: return Color(p_v, p, q);
	}
}

} // namespace

Color evaluate_texture(const Texture &p_texture, double p_u_m, double p_v_m) {
	const double c = std::cos(p_texture.angle_rad), s = std::sin(p_texture.angle_rad);
	const double scale = p_texture.scale_m > 0.0 ? p_texture.scale_m : 1.0;
	const double u = (c * p_u_m + s * p_v_m) / scale;
	const double v = (-s * p_u_m + c * p_v_m) / scale;
	const Color &a = p_texture.a, &b = p_texture.b;
	const uint32_t seed = p_texture.seed;
	switch (p_texture.pattern) {
		case Pattern::Solid:
			return a;
		case Pattern::Checker:
			return ((floor_i(u) + floor_i(v)) & 1) ? b : a;
		case Pattern::Stripes:
			return (floor_i(u) & 1) ? b : a;
		case Pattern::Bricks: {
			const int64_t row = floor_i(v);
			const double bu = u * 0.5 + ((row & 1) ? 0.5 : 0.0);
			const int64_t col = floor_i(bu);
			const double fu = (bu - std::floor(bu)) * 2.0, fv = v - std::floor(v); // in brick heights
			const double mortar = 0.08;
			if (fv < mortar || fu < mortar) {
				return mix(a, Color(0.8f, 0.78f, 0.72f), 0.85);
			}
			return mix(a, b, hash01(col, row, seed));
		}
		case Pattern::Parquet: {
			const int64_t row = floor_i(v);
			const double pu = u / 6.0 + hash01(row, 17, seed);
			const int64_t plank = floor_i(pu);
			const double fu = (pu - std::floor(pu)) * 6.0, fv = v - std::floor(v);
			if (fv < 0.05 || fu < 0.05) {
				return a * 0.35f;
			}
			const double tint = hash01(plank, row, seed);
			const double grain = 0.5 + 0.5 * std::sin(fv * 23.0 + 3.0 * value_noise(fu * 0.8, fv * 3.0 + static_cast<double>(plank), seed + 1));
			return mix(a, b, 0.75 * tint + 0.25 * grain);
		}
		case Pattern::Noise: {
			double n = 0.0, amp = 0.5, freq = 1.0;
			for (int octave = 0; octave < 3; ++octave) {
				n += amp * value_noise(u * freq, v * freq, seed + static_cast<uint32_t>(octave) * 101U);
				amp *= 0.5;
				freq *= 2.7;
			}
			n /= 0.875;
			// Sharpened, so the blotches have edges (high frequency).
			return mix(a, b, std::clamp((n - 0.5) * 3.0 + 0.5, 0.0, 1.0));
		}
		case Pattern::Tiles: {
			const int64_t iu = floor_i(u), iv = floor_i(v);
			const double fu = u - std::floor(u), fv = v - std::floor(v);
			if (fu < 0.06 || fv < 0.06) {
				return a * 0.25f;
			}
			return mix(a, b, hash01(iu, iv, seed));
		}
	}
	return a;
}

Color Panorama::lookup(const glm::dvec3 &p_direction) const {
	if (width <= 0 || height <= 0) {
		return Color(0.0f);
	}
	const glm::dvec3 d = glm::normalize(p_direction);
	const double u = 0.5 + std::atan2(d.x, -d.z) / (2.0 * PI);
	const double v = std::acos(std::clamp(d.y, -1.0, 1.0)) / PI;
	const double px = u * width - 0.5, py = std::clamp(v * height - 0.5, 0.0, height - 1.0);
	const double fx = std::floor(px), fy = std::floor(py);
	const double tx = px - fx, ty = py - fy;
	const int x0 = static_cast<int>(((static_cast<int64_t>(fx) % width) + width) % width);
	const int x1 = (x0 + 1) % width;
	const int y0 = static_cast<int>(fy), y1 = std::min(y0 + 1, height - 1);
	auto at = [&](int p_x, int p_y) {
		const float *p = &rgb[(static_cast<size_t>(p_y) * width + p_x) * 3];
		return Color(p[0], p[1], p[2]);
	};
	return mix(mix(at(x0, y0), at(x1, y0), tx), mix(at(x0, y1), at(x1, y1), tx), ty);
}

namespace {

// A panorama's pixels as linear R, G, B floats (CV_32FC3), the format told by the first bytes,
// not the name: a Radiance .hdr ("#?"), an OpenEXR, or a PNG or JPEG (sRGB, undone approximately).
// Errors name p_path.
std::string read_panorama_rgb(const std::string &p_path, cv::Mat *r_rgb) {
	uint8_t magic[4] = { 0 };
	std::ifstream file(p_path, std::ios::binary);
	if (!file) {
		return p_path + ": cannot be opened for reading";
	}
	file.read(reinterpret_cast<char *>(magic), sizeof(magic));
	if (file.gcount() == 0) {
		return p_path + ": an empty file, not an image";
	}
	file.close();
	if (magic[0] == '#' && magic[1] == '?') {
		return radiance_hdr_read(p_path, r_rgb);
	}
	if (magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) {
		return recording_io::read_exr_rgb(p_path, r_rgb);
	}
	const bool png = magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G';
	if (!png && !(magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF)) {
		return p_path + ": not a Radiance .hdr, OpenEXR, PNG or JPEG file";
	}
	cv::Mat image;
	const std::string error = image_read(p_path, ImageReadMode::Unchanged, &image);
	if (!error.empty()) {
		return error;
	}
	if (image.channels() != 3) {
		return p_path + ": the panorama must have 3 channels, it has " + std::to_string(image.channels());
	}
	// An LDR image: undo sRGB approximately (gamma 2.2). OpenCV's order is B, G, R.
	image.convertTo(image, CV_32F, 1.0 / (image.depth() == CV_16U ? 65535.0 : 255.0));
	cv::pow(image, 2.2, image);
	cv::cvtColor(image, *r_rgb, cv::COLOR_BGR2RGB);
	return "";
}

} // namespace

PanoramaLoadResult load_panorama(const std::string &p_path) {
	PanoramaLoadResult result;
	const std::string not_a_file = input_file_problem(p_path, "no such file");
	if (!not_a_file.empty()) {
		result.error = not_a_file + ", so the panorama cannot be read";
		return result;
	}
	cv::Mat linear;
	const std::string error = read_panorama_rgb(p_path, &linear);
	if (!error.empty()) {
		result.error = error + ", so the panorama cannot be read";
		return result;
	}
	auto panorama = std::make_shared<Panorama>();
	panorama->width = linear.cols;
	panorama->height = linear.rows;
	panorama->rgb.resize(static_cast<size_t>(linear.cols) * linear.rows * 3);
	for (int y = 0; y < linear.rows; ++y) {
		const cv::Vec3f *row = linear.ptr<cv::Vec3f>(y);
		for (int x = 0; x < linear.cols; ++x) {
			float *p = &panorama->rgb[(static_cast<size_t>(y) * linear.cols + x) * 3];
			// Negative values (and NaN) as 0.
			p[0] = std::max(0.0f, row[x][0]);
			p[1] = std::max(0.0f, row[x][1]);
			p[2] = std::max(0.0f, row[x][2]);
		}
	}
	result.ok = true;
	result.panorama = std::move(panorama);
	return result;
}

Color screen_content(double p_x, double p_y, double p_time_s) {
	const double t = p_time_s;
	// A bright square on a Lissajous path.
	const double sx = 0.5 + 0.35 * std::sin(2.0 * PI * t / 3.1);
	const double sy = 0.35 + 0.2 * std::sin(2.0 * PI * t / 2.3 + 1.0);
	if (std::abs(p_x - sx) < 0.08 && std::abs(p_y - sy) < 0.12) {
		return Color(1.0f, 1.0f, 0.95f);
	}
	// A thin frame.
	if (p_x < 0.02 || p_x > 0.98 || p_y < 0.03 || p_y > 0.97) {
		return Color(0.85f);
	}
	if (p_y > 0.7) {
		// Colour bars, shifting by one bar every half second.
		const int64_t bar = floor_i(p_x * 7.0) + floor_i(t * 2.0);
		return hsv(static_cast<double>(bar % 7) / 7.0, 0.9, 0.9);
	}
	// A drifting hue with diagonal stripes.
	const double stripe = std::sin((p_x + p_y) * 40.0 - t * 6.0) > 0.0 ? 1.0 : 0.6;
	return hsv(t / 6.0 + 0.3 * p_x, 0.7, 0.7 * stripe);
}

int add_material(Scene *r_scene, const Material &p_material) {
	r_scene->materials.push_back(p_material);
	return static_cast<int>(r_scene->materials.size()) - 1;
}

namespace {

// Loads the panorama at p_path into r_scene; false with r_error set when it cannot be read.
bool load_scene_panorama(const std::string &p_path, Scene *r_scene, std::string *r_error) {
	PanoramaLoadResult panorama = load_panorama(p_path);
	if (!panorama.ok) {
		*r_error = panorama.error;
		return false;
	}
	r_scene->panorama = panorama.panorama;
	return true;
}

Material textured(const std::string &p_name, Pattern p_pattern, Color p_a, Color p_b, double p_scale_m, double p_angle_rad = 0.0, uint32_t p_seed = 0) {
	Material m;
	m.name = p_name;
	m.albedo.pattern = p_pattern;
	m.albedo.a = p_a;
	m.albedo.b = p_b;
	m.albedo.scale_m = p_scale_m;
	m.albedo.angle_rad = p_angle_rad;
	m.albedo.seed = p_seed;
	return m;
}

Material emissive(const std::string &p_name, Emission p_kind, Color p_scale) {
	Material m;
	m.name = p_name;
	m.albedo.a = Color(0.0f);
	m.emission = p_kind;
	m.emission_scale = p_scale;
	return m;
}

Box box_from_min_max(glm::dvec3 p_min, glm::dvec3 p_max, int p_material, int p_top = -1, double p_yaw = 0.0) {
	Box box;
	box.center = 0.5 * (p_min + p_max);
	box.half_size = 0.5 * (p_max - p_min);
	box.material = p_material;
	box.top_material = p_top;
	box.yaw_rad = p_yaw;
	return box;
}

// A table of top size (w, d) at height h, centred on (x, z), with four legs.
void add_table(Scene *r_scene, double p_x, double p_z, double p_w, double p_d, double p_h, int p_top, int p_legs) {
	const double thick = 0.04, leg = 0.05;
	r_scene->boxes.push_back(box_from_min_max({ p_x - p_w / 2, p_h - thick, p_z - p_d / 2 }, { p_x + p_w / 2, p_h, p_z + p_d / 2 }, p_legs, p_top));
	for (int i = 0; i < 4; ++i) {
		const double lx = p_x + ((i & 1) ? 1 : -1) * (p_w / 2 - 0.06);
		const double lz = p_z + ((i & 2) ? 1 : -1) * (p_d / 2 - 0.06);
		r_scene->boxes.push_back(box_from_min_max({ lx - leg / 2, 0.0, lz - leg / 2 }, { lx + leg / 2, p_h - thick, lz + leg / 2 }, p_legs));
	}
}

// Objects on a table top at height h around (x, z); the probe sits among them.
void add_table_objects(Scene *r_scene, double p_x, double p_z, double p_h) {
	const int red_checker = add_material(r_scene, textured("box_checker", Pattern::Checker, { 0.65f, 0.05f, 0.04f }, { 0.85f, 0.85f, 0.8f }, 0.04));
	const int yellow_stripes = add_material(r_scene, textured("sphere_stripes", Pattern::Stripes, { 0.75f, 0.6f, 0.05f }, { 0.03f, 0.03f, 0.03f }, 0.03, 0.3));
	const int green_tiles = add_material(r_scene, textured("tall_tiles", Pattern::Tiles, { 0.1f, 0.5f, 0.15f }, { 0.5f, 0.8f, 0.3f }, 0.03, 0.0, 7));
	const int book = add_material(r_scene, textured("book", Pattern::Stripes, { 0.1f, 0.2f, 0.6f }, { 0.7f, 0.7f, 0.2f }, 0.02, 1.5708));
	r_scene->boxes.push_back(box_from_min_max({ p_x - 0.47, p_h, p_z + 0.05 }, { p_x - 0.22, p_h + 0.2, p_z + 0.25 }, red_checker, -1, 0.0));
	Sphere sphere;
	sphere.center = { p_x + 0.35, p_h + 0.1, p_z - 0.15 };
	sphere.radius = 0.1;
	sphere.material = yellow_stripes;
	r_scene->spheres.push_back(sphere);
	r_scene->boxes.push_back(box_from_min_max({ p_x + 0.22, p_h, p_z + 0.18 }, { p_x + 0.30, p_h + 0.32, p_z + 0.26 }, green_tiles));
	Box b = box_from_min_max({ p_x - 0.42, p_h, p_z - 0.32 }, { p_x - 0.18, p_h + 0.04, p_z - 0.15 }, book, -1, 0.0);
	b.yaw_rad = 0.35;
	r_scene->boxes.push_back(b);
}

// A ceiling panel light: the Rect light and its emissive panel just under the ceiling.
void add_ceiling_light(Scene *r_scene, double p_x, double p_z, double p_ceiling, double p_half, Color p_radiance, Color p_ambient, double p_on_from_s, int p_samples) {
	Material panel = textured("ceiling_light", Pattern::Solid, Color(0.8f), Color(0.8f), 1.0);
	panel.emission = Emission::Constant;
	panel.emission_scale = p_radiance;
	panel.on_from_s = p_on_from_s;
	const int material = add_material(r_scene, panel);
	const double y = p_ceiling - 0.015;
	Quad quad;
	quad.corner = { p_x - p_half, y, p_z - p_half };
	quad.edge_u = { 2 * p_half, 0.0, 0.0 };
	quad.edge_v = { 0.0, 0.0, 2 * p_half };
	quad.material = material;
	r_scene->quads.push_back(quad);
	// A housing around the panel, so it reads as a fixture.
	const int housing = add_material(r_scene, textured("light_housing", Pattern::Solid, Color(0.3f), Color(0.3f), 1.0));
	r_scene->boxes.push_back(box_from_min_max({ p_x - p_half - 0.03, y + 0.001, p_z - p_half - 0.03 }, { p_x + p_half + 0.03, p_ceiling - 0.001, p_z + p_half + 0.03 }, housing));
	Light light;
	light.kind = LightKind::Rect;
	// Emits downwards: cross(edge_u, edge_v) must point to -Y.
	light.position = { p_x - p_half, y - 0.002, p_z - p_half };
	light.edge_u = { 2 * p_half, 0.0, 0.0 };
	light.edge_v = { 0.0, 0.0, 2 * p_half };
	light.power = p_radiance;
	light.samples_u = p_samples;
	light.samples_v = p_samples;
	light.ambient = p_ambient;
	light.on_from_s = p_on_from_s;
	r_scene->lights.push_back(light);
}

Material ceiling_material() {
	return textured("ceiling", Pattern::Tiles, { 0.85f, 0.84f, 0.78f }, { 0.55f, 0.62f, 0.75f }, 0.5, 0.0, 11);
}

Material floor_material() {
	return textured("floor_parquet", Pattern::Parquet, { 0.5f, 0.28f, 0.1f }, { 0.22f, 0.11f, 0.04f }, 0.09, 0.0, 5);
}

SceneResult make_two_rooms(const SceneOptions &) {
	SceneResult result;
	Scene &scene = result.scene;
	scene.name = "two_rooms";
	scene.has_room = true;
	scene.room.floorplan = figure4_two_rooms();
	const double ceiling = scene.room.floorplan.ceiling_height_m;
	// One distinct high-frequency texture per wall (8 walls, see figure4_two_rooms()).
	scene.room.wall_materials = {
		add_material(&scene, textured("wall0_stripes", Pattern::Stripes, { 0.6f, 0.08f, 0.06f }, { 0.75f, 0.7f, 0.6f }, 0.08)),
		add_material(&scene, textured("wall1_partition_checker", Pattern::Checker, { 0.08f, 0.15f, 0.55f }, { 0.8f, 0.8f, 0.8f }, 0.15)),
		add_material(&scene, textured("wall2_partition_end", Pattern::Stripes, { 0.7f, 0.6f, 0.1f }, { 0.1f, 0.1f, 0.1f }, 0.03, 0.785)),
		add_material(&scene, textured("wall3_partition_bricks", Pattern::Bricks, { 0.55f, 0.25f, 0.12f }, { 0.35f, 0.12f, 0.06f }, 0.075, 0.0, 3)),
		add_material(&scene, textured("wall4_tiles", Pattern::Tiles, { 0.1f, 0.45f, 0.45f }, { 0.8f, 0.85f, 0.85f }, 0.2, 0.0, 4)),
		add_material(&scene, textured("wall5_noise", Pattern::Noise, { 0.1f, 0.4f, 0.12f }, { 0.55f, 0.7f, 0.3f }, 0.06, 0.0, 6)),
		add_material(&scene, textured("wall6_checker", Pattern::Checker, { 0.55f, 0.1f, 0.45f }, { 0.6f, 0.6f, 0.6f }, 0.25, 0.785)),
		add_material(&scene, textured("wall7_stripes", Pattern::Stripes, { 0.05f, 0.08f, 0.3f }, { 0.8f, 0.45f, 0.1f }, 0.1, 1.5708)),
	};
	scene.room.floor_material = add_material(&scene, floor_material());
	scene.room.ceiling_material = add_material(&scene, ceiling_material());

	const double tx = 2.0, tz = 2.0, th = 0.75;
	const int table_top = add_material(&scene, textured("table_top", Pattern::Noise, { 0.55f, 0.5f, 0.42f }, { 0.3f, 0.25f, 0.18f }, 0.03, 0.0, 21));
	const int table_legs = add_material(&scene, textured("table_legs", Pattern::Solid, Color(0.15f), Color(0.15f), 1.0));
	add_table(&scene, tx, tz, 1.2, 0.8, th, table_top, table_legs);
	add_table_objects(&scene, tx, tz, th);

	// Furniture that occludes walls: a wardrobe in the left room, a bookshelf and a sofa in the right.
	const int wardrobe = add_material(&scene, textured("wardrobe", Pattern::Stripes, { 0.35f, 0.2f, 0.1f }, { 0.5f, 0.32f, 0.16f }, 0.05, 1.5708));
	scene.boxes.push_back(box_from_min_max({ 0.05, 0.0, 3.7 }, { 0.65, 2.1, 4.45 }, wardrobe));
	const int shelf = add_material(&scene, textured("bookshelf", Pattern::Tiles, { 0.6f, 0.1f, 0.1f }, { 0.1f, 0.3f, 0.7f }, 0.12, 0.0, 31));
	scene.boxes.push_back(box_from_min_max({ 5.5, 0.0, 4.1 }, { 7.5, 1.8, 4.45 }, shelf));
	const int sofa = add_material(&scene, textured("sofa", Pattern::Noise, { 0.45f, 0.05f, 0.08f }, { 0.25f, 0.02f, 0.04f }, 0.04, 0.0, 41));
	scene.boxes.push_back(box_from_min_max({ 5.2, 0.0, 0.4 }, { 7.2, 0.45, 1.3 }, sofa));
	scene.boxes.push_back(box_from_min_max({ 5.2, 0.45, 0.1 }, { 7.2, 0.9, 0.4 }, sofa));

	add_ceiling_light(&scene, 2.0, 2.2, ceiling, 0.25, Color(14.0f, 13.0f, 11.0f), Color(0.0f), -ALWAYS, 1);
	add_ceiling_light(&scene, 6.0, 2.6, ceiling, 0.25, Color(12.0f, 12.0f, 14.0f), Color(0.0f), -ALWAYS, 1);

	scene.ambient = Color(0.16f, 0.16f, 0.17f);
	scene.background = Color(0.0f);
	scene.probe_position = { tx, th + 0.15, tz };
	scene.look_target = { tx, th + 0.1, tz };
	scene.orbit_radius_m = 1.5;
	scene.camera_height_m = 1.45;
	// From beside the table in the left room, through the doorway (x = 4, z 3 to 4.5), into the right room.
	scene.room_sweep.path_xz = { { 1.5, 3.3 }, { 4.0, 3.75 }, { 6.3, 2.7 } };
	result.ok = true;
	return result;
}

SceneResult make_living_room(const SceneOptions &p_options) {
	SceneResult result;
	Scene &scene = result.scene;
	scene.name = "living_room";
	if (!p_options.panorama_path.empty() && !load_scene_panorama(p_options.panorama_path, &scene, &result.error)) {
		return result;
	}
	scene.has_room = true;
	scene.room.floorplan = living_room();
	const double ceiling = scene.room.floorplan.ceiling_height_m;
	scene.room.wall_materials = {
		add_material(&scene, textured("wall0_window_stripes", Pattern::Stripes, { 0.3f, 0.55f, 0.3f }, { 0.8f, 0.8f, 0.75f }, 0.1)),
		add_material(&scene, textured("wall1_screen_bricks", Pattern::Bricks, { 0.6f, 0.3f, 0.15f }, { 0.4f, 0.15f, 0.08f }, 0.075, 0.0, 2)),
		add_material(&scene, textured("wall2_checker", Pattern::Checker, { 0.1f, 0.2f, 0.6f }, { 0.8f, 0.8f, 0.8f }, 0.2)),
		add_material(&scene, textured("wall3_noise", Pattern::Noise, { 0.7f, 0.4f, 0.08f }, { 0.4f, 0.15f, 0.05f }, 0.07, 0.0, 9)),
	};
	scene.room.floor_material = add_material(&scene, floor_material());
	scene.room.ceiling_material = add_material(&scene, ceiling_material());

	const double tx = 2.5, tz = 2.0, th = 0.75;
	const int table_top = add_material(&scene, textured("table_top", Pattern::Noise, { 0.55f, 0.5f, 0.42f }, { 0.3f, 0.25f, 0.18f }, 0.03, 0.0, 21));
	const int table_legs = add_material(&scene, textured("table_legs", Pattern::Solid, Color(0.15f), Color(0.15f), 1.0));
	add_table(&scene, tx, tz, 1.2, 0.8, th, table_top, table_legs);
	add_table_objects(&scene, tx, tz, th);

	// The window on wall 0 (z = 0), a view onto the panorama.
	const int window = add_material(&scene, emissive("window", Emission::Panorama, Color(1.0f)));
	Quad window_quad;
	window_quad.corner = { 1.2, 2.1, 0.004 };
	window_quad.edge_u = { 1.6, 0.0, 0.0 };
	window_quad.edge_v = { 0.0, -1.2, 0.0 };
	window_quad.material = window;
	scene.quads.push_back(window_quad);
	const int frame = add_material(&scene, textured("window_frame", Pattern::Solid, Color(0.85f), Color(0.85f), 1.0));
	scene.boxes.push_back(box_from_min_max({ 1.15, 0.84, 0.0 }, { 2.85, 0.9, 0.12 }, frame)); // sill
	scene.boxes.push_back(box_from_min_max({ 1.97, 0.9, 0.0 }, { 2.03, 2.1, 0.03 }, frame)); // mullion

	// The screen on wall 1 (x = 5), seen from inside looking +X: right is +Z, down is -Y.
	const int bezel = add_material(&scene, textured("screen_bezel", Pattern::Solid, Color(0.04f), Color(0.04f), 1.0));
	scene.boxes.push_back(box_from_min_max({ 4.94, 0.93, 1.38 }, { 5.0, 1.57, 2.42 }, bezel));
	Material screen = emissive("screen", Emission::Screen, Color(1.2f));
	screen.screen_width_m = 1.0;
	screen.screen_height_m = 0.6;
	const int screen_material = add_material(&scene, screen);
	Quad screen_quad;
	screen_quad.corner = { 4.935, 1.55, 1.4 };
	screen_quad.edge_u = { 0.0, 0.0, 1.0 };
	screen_quad.edge_v = { 0.0, -0.6, 0.0 };
	screen_quad.material = screen_material;
	scene.quads.push_back(screen_quad);
	scene.boxes.push_back(box_from_min_max({ 4.55, 0.0, 1.3 }, { 4.95, 0.5, 2.5 }, add_material(&scene, textured("tv_bench", Pattern::Stripes, { 0.2f, 0.2f, 0.22f }, { 0.5f, 0.5f, 0.5f }, 0.04))));

	// A sofa along wall 3, a bookshelf on wall 2.
	const int sofa = add_material(&scene, textured("sofa", Pattern::Noise, { 0.45f, 0.05f, 0.08f }, { 0.25f, 0.02f, 0.04f }, 0.04, 0.0, 41));
	scene.boxes.push_back(box_from_min_max({ 0.35, 0.0, 1.0 }, { 0.9, 0.45, 3.0 }, sofa));
	scene.boxes.push_back(box_from_min_max({ 0.05, 0.0, 1.0 }, { 0.35, 0.9, 3.0 }, sofa));
	const int shelf = add_material(&scene, textured("bookshelf", Pattern::Tiles, { 0.6f, 0.1f, 0.1f }, { 0.1f, 0.3f, 0.7f }, 0.12, 0.0, 31));
	scene.boxes.push_back(box_from_min_max({ 0.3, 0.0, 3.65 }, { 1.3, 1.9, 4.0 }, shelf));

	// A floor lamp (always on) in the corner by the screen.
	const int pole = add_material(&scene, textured("lamp_pole", Pattern::Solid, Color(0.1f), Color(0.1f), 1.0));
	scene.boxes.push_back(box_from_min_max({ 4.38, 0.0, 3.38 }, { 4.42, 1.55, 3.42 }, pole));
	Material shade = textured("lamp_shade", Pattern::Solid, Color(0.9f), Color(0.9f), 1.0);
	shade.emission = Emission::Constant;
	shade.emission_scale = Color(2.5f, 2.1f, 1.6f);
	Sphere lamp;
	lamp.center = { 4.4, 1.7, 3.4 };
	lamp.radius = 0.15;
	lamp.material = add_material(&scene, shade);
	scene.spheres.push_back(lamp);
	Light lamp_light;
	lamp_light.kind = LightKind::Point;
	lamp_light.position = lamp.center;
	lamp_light.power = Color(3.0f, 2.6f, 2.0f);
	lamp_light.shadow_skip_m = lamp.radius + 0.01;
	scene.lights.push_back(lamp_light);

	// The ceiling light above the table, switched on half-way.
	const double switch_s = 0.5 * p_options.duration_s;
	add_ceiling_light(&scene, tx, tz, ceiling, 0.3, Color(25.0f, 24.0f, 21.0f), Color(0.2f, 0.19f, 0.17f), switch_s, 2);
	scene.ceiling_light_center = { tx, ceiling - 0.015, tz };
	scene.ceiling_light_half_size_m = 0.3;
	scene.light_switch_s = switch_s;

	scene.ambient = Color(0.12f, 0.12f, 0.13f);
	scene.background = Color(0.0f);
	scene.probe_position = { tx, th + 0.15, tz };
	scene.look_target = { tx, th + 0.1, tz };
	scene.orbit_radius_m = 1.5;
	scene.camera_height_m = 1.45;
	// Round the table (x 1.9 to 3.1, z 1.6 to 2.4), between it and the sofa, then the screen.
	scene.room_sweep.path_xz = { { 1.4, 1.0 }, { 3.7, 1.1 }, { 3.6, 3.1 } };
	result.ok = true;
	return result;
}

SceneResult make_panorama_room(const SceneOptions &p_options) {
	SceneResult result;
	Scene &scene = result.scene;
	scene.name = "panorama_room";
	if (p_options.panorama_path.empty()) {
		result.error = "panorama_room needs a panorama (SceneOptions::panorama_path, --hdri)";
		return result;
	}
	if (!load_scene_panorama(p_options.panorama_path, &scene, &result.error)) {
		return result;
	}
	scene.has_room = true;
	scene.room.floorplan = living_room();
	scene.room.floorplan.ceiling_height_m = 2.6;
	const double width = 5.0, depth = 4.0, ceiling = scene.room.floorplan.ceiling_height_m;
	const glm::dvec3 centre(0.5 * width, 0.5 * ceiling, 0.5 * depth);
	// Unlit: what the RGB camera sees is the photograph itself, with no shading to confuse a
	// photometric term, and the cubemap at the centre is the panorama (times the scale).
	scene.panorama_center = centre;
	scene.panorama_scale = panorama_exposure_scale(*scene.panorama);
	Material painted = emissive("panorama", Emission::ProjectedPanorama, Color(static_cast<float>(scene.panorama_scale)));
	painted.unlit = true;
	const int material = add_material(&scene, painted);
	scene.room.wall_materials = { material };
	scene.room.floor_material = material;
	scene.room.ceiling_material = material;
	scene.ambient = Color(0.0f);
	scene.background = Color(0.0f);
	scene.probe_position = centre;
	scene.look_target = centre;
	scene.camera_height_m = 1.4;
	// In front of wall 0 (z = 0, the panorama's middle: -Z is its centre column), 1.5 m away:
	// with the RGB-D camera's 63 x 49 degree view, the wall fills the frame.
	scene.trajectory = TrajectoryKind::WallSweep;
	scene.wall_sweep.wall_point = { 0.5 * width, 0.0, 0.0 };
	scene.wall_sweep.normal = { 0.0, 0.0, 1.0 };
	scene.wall_sweep.half_length_m = 0.9;
	scene.wall_sweep.distance_m = 1.5;
	scene.room_sweep.path_xz = { { 1.8, 1.5 }, { 3.2, 2.5 } };
	result.ok = true;
	return result;
}

} // namespace

double panorama_exposure_scale(const Panorama &p_panorama) {
	// Rows weighted by sin(polar angle), the solid angle of their texels.
	double log_sum = 0.0, weight_sum = 0.0;
	for (int y = 0; y < p_panorama.height; ++y) {
		const double weight = std::sin(PI * (y + 0.5) / p_panorama.height);
		for (int x = 0; x < p_panorama.width; ++x) {
			const float *p = &p_panorama.rgb[(static_cast<size_t>(y) * p_panorama.width + x) * 3];
			const double luminance = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
			log_sum += weight * std::log(1e-4 + luminance); // the offset keeps black texels finite
			weight_sum += weight;
		}
	}
	if (!(weight_sum > 0.0)) {
		return 1.0;
	}
	return PANORAMA_KEY / std::exp(log_sum / weight_sum);
}

const char *trajectory_name(TrajectoryKind p_kind) {
	switch (p_kind) {
		case TrajectoryKind::WallSweep:
			return "wall_sweep";
		case TrajectoryKind::RoomSweep:
			return "room_sweep";
		case TrajectoryKind::Orbit:
			break;
	}
	return "orbit";
}

std::vector<std::string> scene_names() {
	return { "two_rooms", "living_room", "panorama_room" };
}

SceneResult make_scene(const std::string &p_name, const SceneOptions &p_options) {
	if (!(p_options.duration_s > 0.0) || !std::isfinite(p_options.duration_s)) {
		SceneResult result;
		result.error = "the duration must be a positive number of seconds";
		return result;
	}
	if (p_name == "two_rooms") {
		return make_two_rooms(p_options);
	}
	if (p_name == "living_room") {
		return make_living_room(p_options);
	}
	if (p_name == "panorama_room") {
		return make_panorama_room(p_options);
	}
	SceneResult result;
	result.error = "unknown scene '" + p_name + "' (known: two_rooms, living_room, panorama_room)";
	return result;
}

} // namespace roomprobe::synth
