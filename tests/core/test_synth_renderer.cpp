// The synthetic rig's ray tracer (extension/core/synth/), checked against geometry: depth of known
// planes and its noise model, holes, the fisheye's image circle, the same wall point seen by both
// cameras, the light switch, determinism.

#include "io/opencv.h"

#include "camera/omni_camera.h"
#include "camera/pinhole_camera.h"
#include "rig/rig.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

using namespace roomprobe;
using namespace roomprobe::synth;

namespace {

// A scene holding one flat-lit quad, a plane through p_point with normal p_normal, 20 m wide.
Scene plane_scene(const glm::dvec3 &p_point, const glm::dvec3 &p_normal) {
	Scene scene;
	Material material;
	material.albedo.a = Color(0.5f);
	material.unlit = true;
	add_material(&scene, material);
	const glm::dvec3 n = glm::normalize(p_normal);
	const glm::dvec3 helper = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
	const glm::dvec3 u = glm::normalize(glm::cross(n, helper)), v = glm::cross(n, u);
	Quad quad;
	quad.corner = p_point - 10.0 * u - 10.0 * v;
	quad.edge_u = 20.0 * u;
	quad.edge_v = 20.0 * v;
	quad.material = 0;
	scene.quads.push_back(quad);
	return scene;
}

struct Stats {
	double mean = 0.0, std = 0.0;
	size_t count = 0, holes = 0;
};

Stats depth_error_stats(const RgbdImage &p_image, double p_scale, double p_truth_z) {
	Stats s;
	double sum = 0.0, sum2 = 0.0;
	for (int y = 0; y < p_image.depth.rows; ++y) {
		for (int x = 0; x < p_image.depth.cols; ++x) {
			const uint16_t d = p_image.depth.at<uint16_t>(y, x);
			if (d == 0) {
				++s.holes;
				continue;
			}
			const double e = d * p_scale - p_truth_z;
			sum += e;
			sum2 += e * e;
			++s.count;
		}
	}
	s.mean = sum / s.count;
	s.std = std::sqrt(sum2 / s.count - s.mean * s.mean);
	return s;
}

cv::Vec3b srgb8(const Color &p_linear) {
	return cv::Vec3b(linear_to_srgb8(p_linear.r), linear_to_srgb8(p_linear.g), linear_to_srgb8(p_linear.b));
}

int max_channel_difference(const cv::Vec3b &p_a, const cv::Vec3b &p_b) {
	int d = 0;
	for (int c = 0; c < 3; ++c) {
		d = std::max(d, std::abs(int(p_a[c]) - int(p_b[c])));
	}
	return d;
}

Scene reference_scene(const std::string &p_name, double p_duration_s = 10.0) {
	SceneOptions options;
	options.duration_s = p_duration_s;
	const SceneResult result = make_scene(p_name, options); // no panorama: a procedural sky
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.scene;
}

} // namespace

TEST_CASE("synth: the noise model is Nguyen et al.'s axial sigma") {
	CHECK(kinect_depth_sigma_m(0.4) == doctest::Approx(0.0012));
	CHECK(kinect_depth_sigma_m(2.4) == doctest::Approx(0.0012 + 0.0019 * 4.0));
}

TEST_CASE("synth: depth of a fronto-parallel plane agrees with the truth within the noise model") {
	const Rig rig = test_rig();
	for (double z : { 0.8, 1.5, 3.0 }) {
		CAPTURE(z);
		// The camera at the origin looking along +z (identity pose); the plane z = const.
		const SynthRenderer renderer(plane_scene({ 0.0, 0.0, z }, { 0.0, 0.0, -1.0 }));
		REQUIRE(renderer.ok());
		RgbdOptions options;
		options.noise_seed = 42;
		const RgbdImage image = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, Pose(), 0.0, options);
		const Stats s = depth_error_stats(image, rig.depth_scale_m, z);
		CHECK(s.holes == 0);
		CHECK(std::abs(s.mean) < 0.001);
		const double sigma = kinect_depth_sigma_m(z);
		CHECK(s.std > 0.8 * sigma);
		CHECK(s.std < 1.2 * sigma);
		// The noise-free depth is z itself, at every pixel.
		double worst = 0.0;
		for (int y = 0; y < image.depth_true_m.rows; ++y) {
			for (int x = 0; x < image.depth_true_m.cols; ++x) {
				worst = std::max(worst, std::abs(image.depth_true_m.at<float>(y, x) - z));
			}
		}
		CHECK(worst < 1e-5);

		options.depth_noise = false;
		const RgbdImage clean = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, Pose(), 0.0, options);
		const Stats c = depth_error_stats(clean, rig.depth_scale_m, z);
		CHECK(c.std < 1e-9);
		CHECK(std::abs(c.mean) <= 0.0005 + 1e-9); // quantised to mm
	}
}

TEST_CASE("synth: depth is z along the optical axis, not the ray length (a tilted plane, posed camera)") {
	const Rig rig = test_rig();
	// A camera somewhere in the world, and a plane 2 m in front of it, tilted by 35 degrees.
	Pose world_from_camera;
	world_from_camera.rotation = glm::angleAxis(0.6, glm::normalize(glm::dvec3(0.2, 1.0, 0.1)));
	world_from_camera.translation = { 1.0, 1.4, -0.5 };
	const glm::dmat3 r = glm::mat3_cast(world_from_camera.rotation);
	const glm::dvec3 n_camera = glm::normalize(glm::dvec3(std::sin(0.61), 0.0, -std::cos(0.61)));
	const glm::dvec3 p_camera(0.0, 0.0, 2.0);
	const SynthRenderer renderer(plane_scene(transform_point(world_from_camera, p_camera), r * n_camera));
	REQUIRE(renderer.ok());
	RgbdOptions options;
	options.depth_noise = false;
	const RgbdImage image = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, world_from_camera, 0.0, options);
	int checked = 0;
	for (int y = 5; y < 480; y += 47) {
		for (int x = 5; x < 640; x += 53) {
			const glm::dvec3 ray = unproject_pinhole(rig.rgb, glm::dvec2(x, y));
			const double t = glm::dot(p_camera, n_camera) / glm::dot(ray, n_camera); // z, since ray.z = 1
			CHECK(image.depth_true_m.at<float>(y, x) == doctest::Approx(t).epsilon(1e-5));
			const uint16_t d = image.depth.at<uint16_t>(y, x);
			if (d != 0) {
				CHECK(std::abs(d * 0.001 - t) <= 0.0005 + 1e-6);
				++checked;
			}
		}
	}
	CHECK(checked > 100);
}

TEST_CASE("synth: no depth reading at grazing angles") {
	const Rig rig = test_rig();
	// A floor 0.5 m below the camera (the camera's +y is down): rays near the horizon graze it.
	const SynthRenderer renderer(plane_scene({ 0.0, 0.5, 0.0 }, { 0.0, -1.0, 0.0 }));
	REQUIRE(renderer.ok());
	RgbdOptions options;
	options.noise_seed = 7;
	const RgbdImage image = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, Pose(), 0.0, options);
	int grazing_holes = 0, grazing = 0, steep_readings = 0, steep = 0;
	for (int y = 241; y < 480; ++y) {
		for (int x = 0; x < 640; x += 7) {
			const glm::dvec3 ray = unproject_pinhole(rig.rgb, glm::dvec2(x, y));
			const double angle = std::acos(ray.y / glm::length(ray)) * 180.0 / std::numbers::pi;
			const double z = 0.5 / ray.y;
			if (z > 7.5) {
				continue; // beyond the range
			}
			const bool hole = image.depth.at<uint16_t>(y, x) == 0;
			if (angle > 76.0) {
				++grazing;
				grazing_holes += hole;
			} else if (angle < 74.0) {
				++steep;
				steep_readings += !hole;
			}
		}
	}
	CHECK(grazing > 500);
	CHECK(steep > 500);
	CHECK(grazing_holes == grazing);
	CHECK(steep_readings == steep);
}

TEST_CASE("synth: holes on the far side of depth discontinuities and in the projector's shadow") {
	const Rig rig = test_rig();
	// A wall at 2.5 m and a box in front of it at 1 m.
	Scene scene = plane_scene({ 0.0, 0.0, 2.5 }, { 0.0, 0.0, -1.0 });
	Box box;
	box.center = { 0.0, 0.0, 1.1 };
	box.half_size = { 0.15, 0.15, 0.1 };
	box.material = 0;
	scene.boxes.push_back(box);
	const SynthRenderer renderer(scene);
	REQUIRE(renderer.ok());
	RgbdOptions options;
	options.depth_noise = false;
	const RgbdImage image = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, Pose(), 0.0, options);
	const int row = 240;
	// The box's front face spans x in [-0.15, 0.15] at z = 1: columns 319.5 +- 78.75.
	const int left_edge = static_cast<int>(std::floor(319.5 - 525.0 * 0.15 / 1.0));
	const int right_edge = static_cast<int>(std::ceil(319.5 + 525.0 * 0.15 / 1.0));
	CHECK(image.depth.at<uint16_t>(row, 320) == 1000);
	// The wall right next to the box's silhouette, on either side: no reading.
	// (left_edge and right_edge are the first wall columns outside the box's silhouette.)
	CHECK(image.depth.at<uint16_t>(row, left_edge + 1) == 1000);
	CHECK(image.depth.at<uint16_t>(row, right_edge - 1) == 1000);
	CHECK(image.depth.at<uint16_t>(row, left_edge) == 0);
	CHECK(image.depth.at<uint16_t>(row, right_edge) == 0);
	// The projector sits 7.5 cm along the camera's +x: it cannot see a band of the wall left of the
	// box. Its ray past the box's front-left corner (-0.15, 1) meets the wall at x = 0.075 - 0.225 * 2.5
	// = -0.4875; the camera sees the wall from x = -0.375 leftwards: a band 0.1125 m wide, columns
	// 217.1 to 240.75.
	int shadow = 0;
	for (int x = left_edge - 39; x <= left_edge; ++x) {
		shadow += image.depth.at<uint16_t>(row, x) == 0;
	}
	CHECK(shadow >= 22);
	CHECK(shadow <= 25);
	CHECK(image.depth.at<uint16_t>(row, 216) == 2500);
	CHECK(image.depth.at<uint16_t>(row, 219) == 0);
	// Away from the box the wall reads 2.5 m; on the right only the edge pixel is lost.
	CHECK(image.depth.at<uint16_t>(row, 20) == 2500);
	CHECK(image.depth.at<uint16_t>(row, 620) == 2500);
	CHECK(image.depth.at<uint16_t>(row, right_edge + 1) == 2500);
	CHECK(image.depth.at<uint16_t>(row, right_edge + 10) == 2500);
}

TEST_CASE("synth: the fisheye image is black outside its image circle") {
	const Rig rig = test_rig();
	const Scene scene = reference_scene("two_rooms");
	const SynthRenderer renderer(scene);
	REQUIRE(renderer.ok());
	const HandheldTrajectory trajectory = make_handheld_trajectory(scene, 3);
	const Pose world_from_fisheye = compose(trajectory.world_from_rgb(1.0), rig.rgb_from_fisheye);
	const FisheyeImage image = render_fisheye(renderer, rig.fisheye, world_from_fisheye, 1.0, FisheyeOptions());
	REQUIRE(image.image.type() == CV_8UC3);
	REQUIRE(image.image.cols == 1024);
	size_t outside = 0, outside_black = 0, inside = 0, inside_lit = 0;
	for (int y = 0; y < 1024; ++y) {
		for (int x = 0; x < 1024; ++x) {
			const cv::Vec3b p = image.image.at<cv::Vec3b>(y, x);
			const bool black = p[0] == 0 && p[1] == 0 && p[2] == 0;
			if (!omni_pixel_valid(rig.fisheye, glm::dvec2(x, y))) {
				++outside;
				outside_black += black;
			} else {
				++inside;
				inside_lit += !black;
			}
		}
	}
	CHECK(outside > 200000);
	CHECK(outside_black == outside);
	CHECK(inside_lit > 0.99 * inside);
	// The vignetting darkens towards the edge: the gain is 0.5 at the circle and 1 at the centre.
	CHECK(fisheye_vignetting(rig.fisheye, glm::dvec2(511.5, 511.5), 0.5) == doctest::Approx(1.0));
	CHECK(fisheye_vignetting(rig.fisheye, glm::dvec2(1011.5, 511.5), 0.5) == doctest::Approx(0.5));
}

TEST_CASE("synth: with the true poses, a wall point seen by both cameras has the same colour in both, the texture's") {
	const Rig rig = test_rig();
	for (const std::string name : { "two_rooms", "living_room" }) {
		CAPTURE(name);
		const Scene scene = reference_scene(name);
		SynthRenderer renderer(scene);
		REQUIRE(renderer.ok());
		renderer.set_lighting_enabled(false); // radiance = albedo: the texture's colour
		std::vector<int> wall_materials = scene.room.wall_materials;
		const HandheldTrajectory trajectory = make_handheld_trajectory(scene, 11);
		int checked = 0, matched = 0;
		for (double t : { 0.5, 3.0, 6.5 }) {
			CAPTURE(t);
			const Pose world_from_rgb = trajectory.world_from_rgb(t);
			const Pose world_from_fisheye = compose(world_from_rgb, rig.rgb_from_fisheye);
			RgbdOptions rgbd_options;
			const RgbdImage rgb = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, world_from_rgb, t, rgbd_options);
			FisheyeOptions fisheye_options;
			fisheye_options.vignetting_edge_gain = 1.0; // none, to compare colours
			const FisheyeImage fisheye = render_fisheye(renderer, rig.fisheye, world_from_fisheye, t, fisheye_options);
			const Pose fisheye_from_world = inverse(world_from_fisheye);
			const glm::dmat3 r = glm::mat3_cast(world_from_rgb.rotation);
			for (int y = 4; y < 260; y += 6) {
				for (int x = 4; x < 640; x += 6) {
					// The wall point the RGB pixel sees.
					const glm::dvec3 direction = r * unproject_pinhole(rig.rgb, glm::dvec2(x, y));
					const Hit hit = renderer.intersect(world_from_rgb.translation, direction);
					if (!hit.hit || std::find(wall_materials.begin(), wall_materials.end(), hit.material) == wall_materials.end()) {
						continue;
					}
					// Only where the texture is the same all around (pixel footprints never straddle an edge).
					const Texture &texture = scene.materials[hit.material].albedo;
					const Color c = evaluate_texture(texture, hit.u_m, hit.v_m);
					bool uniform = true;
					for (double du : { -0.025, 0.0, 0.025 }) {
						for (double dv : { -0.025, 0.0, 0.025 }) {
							uniform = uniform && evaluate_texture(texture, hit.u_m + du, hit.v_m + dv) == c;
						}
					}
					if (!uniform) {
						continue;
					}
					// The same point in the fisheye, unless the fisheye cannot see it.
					glm::dvec2 pixel;
					if (!project_omni(rig.fisheye, transform_point(fisheye_from_world, hit.point), &pixel) || !omni_pixel_valid(rig.fisheye, pixel)) {
						continue;
					}
					const glm::dvec3 to_point = hit.point - world_from_fisheye.translation;
					const Hit seen = renderer.intersect(world_from_fisheye.translation, glm::normalize(to_point));
					if (!seen.hit || std::abs(seen.distance - glm::length(to_point)) > 0.005) {
						continue;
					}
					const int px = static_cast<int>(std::lround(pixel.x)), py = static_cast<int>(std::lround(pixel.y));
					if (!omni_pixel_valid(rig.fisheye, glm::dvec2(px, py))) {
						continue;
					}
					const cv::Vec3b expected = srgb8(c);
					const cv::Vec3b in_rgb = rgb.rgb.at<cv::Vec3b>(y, x);
					const cv::Vec3b in_fisheye = fisheye.image.at<cv::Vec3b>(py, px);
					++checked;
					matched += max_channel_difference(in_rgb, expected) <= 1 && max_channel_difference(in_fisheye, expected) <= 1;
				}
			}
		}
		MESSAGE(name << ": " << matched << " of " << checked << " wall points match in both cameras");
		CHECK(checked > 300);
		CHECK(matched >= 0.98 * checked);
	}
}

TEST_CASE("synth: the ceiling light saturates the fisheye after it switches on, and not before") {
	const Rig rig = test_rig();
	const Scene scene = reference_scene("living_room", 10.0);
	REQUIRE(scene.ceiling_light_half_size_m > 0.0);
	CHECK(scene.light_switch_s == doctest::Approx(5.0));
	const SynthRenderer renderer(scene);
	REQUIRE(renderer.ok());
	const HandheldTrajectory trajectory = make_handheld_trajectory(scene, 1);
	int frames = 0;
	for (double t : { 0.5, 4.9, 5.1, 9.5 }) {
		CAPTURE(t);
		const Pose world_from_fisheye = compose(trajectory.world_from_rgb(t), rig.rgb_from_fisheye);
		const FisheyeImage image = render_fisheye(renderer, rig.fisheye, world_from_fisheye, t, FisheyeOptions());
		// The inner half of the panel, projected.
		const Pose fisheye_from_world = inverse(world_from_fisheye);
		int pixels = 0, saturated = 0;
		const double h = 0.5 * scene.ceiling_light_half_size_m;
		for (double du = -h; du <= h + 1e-9; du += h / 4) {
			for (double dv = -h; dv <= h + 1e-9; dv += h / 4) {
				const glm::dvec3 point = scene.ceiling_light_center + glm::dvec3(du, -0.001, dv);
				glm::dvec2 pixel;
				REQUIRE(project_omni(rig.fisheye, transform_point(fisheye_from_world, point), &pixel));
				REQUIRE(omni_pixel_valid(rig.fisheye, pixel));
				const cv::Vec3b p = image.image.at<cv::Vec3b>(static_cast<int>(std::lround(pixel.y)), static_cast<int>(std::lround(pixel.x)));
				++pixels;
				saturated += p[0] == 255 && p[1] == 255 && p[2] == 255;
			}
		}
		if (t < scene.light_switch_s) {
			CHECK(saturated == 0);
		} else {
			CHECK(saturated == pixels);
		}
		++frames;
	}
	CHECK(frames == 4);
}

TEST_CASE("synth: the screen's picture changes over time") {
	CHECK(screen_content(0.3, 0.4, 1.0) != screen_content(0.3, 0.4, 1.7));
	CHECK(screen_content(0.5, 0.85, 0.0) != screen_content(0.5, 0.85, 0.5)); // the bars move
	CHECK(screen_content(0.3, 0.4, 2.0) == screen_content(0.3, 0.4, 2.0));
}

TEST_CASE("synth: cubemaps follow the recording's face layout") {
	// The probe in an unlit room whose walls are solid colours: each face sees the right wall.
	Scene scene;
	scene.has_room = true;
	scene.room.floorplan.points = { { -2, -2 }, { 2, -2 }, { 2, 2 }, { -2, 2 } };
	scene.room.floorplan.ceiling_height_m = 4.0;
	auto solid = [&](Color c) {
		Material m;
		m.albedo.a = c;
		m.unlit = true;
		return add_material(&scene, m);
	};
	// Walls of the normalized floorplan: 0 at z = -2, 1 at x = 2, 2 at z = 2, 3 at x = -2.
	scene.room.wall_materials = { solid({ 0, 0, 0.1f }), solid({ 0.2f, 0, 0 }), solid({ 0, 0, 0.3f }), solid({ 0.4f, 0, 0 }) };
	scene.room.floor_material = solid({ 0, 0.5f, 0 });
	scene.room.ceiling_material = solid({ 0, 0.6f, 0 });
	const SynthRenderer renderer(scene);
	REQUIRE(renderer.ok());
	const auto faces = render_cubemap(renderer, { 0.0, 2.0, 0.0 }, 0.0, 8);
	auto centre = [&](int f) { return faces[f].at<cv::Vec3f>(4, 4); };
	CHECK(centre(0)[0] == doctest::Approx(0.2f)); // +X
	CHECK(centre(1)[0] == doctest::Approx(0.4f)); // -X
	CHECK(centre(2)[1] == doctest::Approx(0.6f)); // +Y: the ceiling
	CHECK(centre(3)[1] == doctest::Approx(0.5f)); // -Y: the floor
	CHECK(centre(4)[2] == doctest::Approx(0.3f)); // +Z
	CHECK(centre(5)[2] == doctest::Approx(0.1f)); // -Z
}

TEST_CASE("synth: rendering is deterministic, and the depth noise follows the seed") {
	const Rig rig = test_rig();
	const Scene scene = reference_scene("living_room");
	const SynthRenderer renderer(scene);
	REQUIRE(renderer.ok());
	const Pose pose = make_handheld_trajectory(scene, 5).world_from_rgb(2.0);
	RgbdOptions options;
	options.noise_seed = 99;
	const RgbdImage a = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, pose, 2.0, options);
	const RgbdImage b = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, pose, 2.0, options);
	CHECK(cv::norm(a.rgb, b.rgb, cv::NORM_INF) == 0);
	CHECK(cv::norm(a.depth, b.depth, cv::NORM_INF) == 0);
	options.noise_seed = 100;
	const RgbdImage c = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, pose, 2.0, options);
	CHECK(cv::norm(a.rgb, c.rgb, cv::NORM_INF) == 0);
	CHECK(cv::norm(a.depth, c.depth, cv::NORM_INF) > 0);
}

TEST_CASE("synth: scene errors are reported") {
	CHECK_FALSE(make_scene("kitchen", SceneOptions()).ok);
	SceneOptions options;
	options.panorama_path = "/nonexistent/panorama.hdr";
	const SceneResult missing = make_scene("living_room", options);
	CHECK_FALSE(missing.ok);
	CHECK(missing.error.find("/nonexistent/panorama.hdr") != std::string::npos);
	Scene bad;
	Quad quad;
	quad.material = 3;
	bad.quads.push_back(quad);
	const SynthRenderer renderer(bad);
	CHECK_FALSE(renderer.ok());
	CHECK(renderer.error().find("material 3") != std::string::npos);
}

TEST_CASE("synth: the window shows the real panorama") {
	const std::string path = std::string(ROOMPROBE_SHARED_DATA) + "/hdri/lebombo_1k.hdr";
	const PanoramaLoadResult panorama = load_panorama(path);
	if (!panorama.ok) {
		MESSAGE("skipped: " << panorama.error);
		return;
	}
	CHECK(panorama.panorama->width == 1024);
	CHECK(panorama.panorama->height == 512);
	SceneOptions options;
	options.panorama_path = path;
	const SceneResult scene = make_scene("living_room", options);
	REQUIRE(scene.ok);
	const SynthRenderer renderer(scene.scene);
	REQUIRE(renderer.ok());
	// A ray through the window (wall z = 0, window x in [1.2, 2.8], y in [0.9, 2.1]) shows the
	// panorama in that direction.
	const glm::dvec3 origin(2.4, 1.5, 2.0), direction = glm::normalize(glm::dvec3(-0.1, 0.05, -1.0));
	Hit hit;
	const Color c = renderer.radiance(origin, direction, 0.0, &hit);
	REQUIRE(hit.hit);
	CHECK(hit.point.z == doctest::Approx(0.004).epsilon(1e-3));
	const Color expected = panorama.panorama->lookup(direction);
	CHECK(c.r == doctest::Approx(expected.r));
	CHECK(c.g == doctest::Approx(expected.g));
	CHECK(c.b == doctest::Approx(expected.b));
}
