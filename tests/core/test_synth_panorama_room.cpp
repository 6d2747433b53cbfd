// The synthetic panorama_room (extension/core/synth/): a bare box painted with a real panorama as
// seen from its centre, and the wall-sweep trajectory in front of one wall; checked against the
// panorama file itself and against geometry. Also the frames of panorama_room_frames.h.
// Skipped, with the reason, when ../shared/data/hdri is missing.

#include "io/opencv.h"

#include "camera/pinhole_camera.h"
#include "types/cubemap_layout.h"
#include "room/floorplan.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "panorama_room_frames.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

using namespace roomprobe;
using namespace roomprobe::synth;

namespace {

constexpr double PI = std::numbers::pi;

// True (and says why) when the panorama is missing: the test is skipped.
bool skip_without_panorama() {
	std::string reason;
	if (panorama_room_frames::available(&reason)) {
		return false;
	}
	MESSAGE("skipped: " << reason);
	return true;
}

// The panorama file as OpenCV reads it, R, G, B linear floats: the ground truth, read apart from
// synth's own loader.
cv::Mat read_panorama_rgb(const std::string &p_path) {
	cv::Mat bgr = cv::imread(p_path, cv::IMREAD_UNCHANGED | cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
	REQUIRE(bgr.type() == CV_32FC3);
	cv::Mat rgb;
	cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
	return rgb;
}

// The direction (world) whose panorama coordinates are the centre of texel (p_col, p_row): the
// image centre looks along -Z, the top row up (synth_scene.h).
glm::dvec3 texel_direction(int p_col, int p_row, int p_width, int p_height) {
	const double phi = 2.0 * PI * ((p_col + 0.5) / p_width - 0.5), theta = PI * (p_row + 0.5) / p_height;
	return { std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi) };
}

double angle_between(const glm::dquat &p_a, const glm::dquat &p_b) {
	return 2.0 * std::acos(std::min(1.0, std::abs(glm::dot(p_a, p_b))));
}

double luminance(const cv::Vec3f &p_rgb) {
	return 0.2126 * p_rgb[0] + 0.7152 * p_rgb[1] + 0.0722 * p_rgb[2];
}

} // namespace

TEST_CASE("synth: panorama_room is a bare box; its exposure is the panorama's key value") {
	if (skip_without_panorama()) {
		return;
	}
	const Scene &scene = panorama_room_frames::room().scene;
	CHECK(scene.has_room);
	CHECK(scene.quads.empty());
	CHECK(scene.boxes.empty());
	CHECK(scene.spheres.empty());
	CHECK(scene.lights.empty());
	CHECK(scene.room.floorplan.points.size() == 4);
	CHECK(check_floorplan(scene.room.floorplan).ok);
	CHECK(scene.room.floorplan.ceiling_height_m == 2.6);
	CHECK(scene.probe_position == glm::dvec3(2.5, 1.3, 2.0));
	CHECK(scene.panorama_center == scene.probe_position);
	CHECK(scene.trajectory == TrajectoryKind::WallSweep);
	// 0.18 over the log-average luminance, by solid angle, of the file itself.
	const cv::Mat pano = read_panorama_rgb(panorama_room_frames::panorama_path());
	double log_sum = 0.0, weight_sum = 0.0;
	for (int y = 0; y < pano.rows; ++y) {
		const double w = std::sin(PI * (y + 0.5) / pano.rows);
		for (int x = 0; x < pano.cols; ++x) {
			log_sum += w * std::log(1e-4 + luminance(pano.at<cv::Vec3f>(y, x)));
			weight_sum += w;
		}
	}
	CHECK(scene.panorama_scale == doctest::Approx(0.18 / std::exp(log_sum / weight_sum)).epsilon(1e-6));
}

TEST_CASE("synth: panorama_room seen from its centre is the panorama file, texel for texel") {
	if (skip_without_panorama()) {
		return;
	}
	const panorama_room_frames::Room &room = panorama_room_frames::room();
	const cv::Mat pano = read_panorama_rgb(panorama_room_frames::panorama_path());
	const double scale = room.scene.panorama_scale;
	// Door, wall light, window, a far wall, the floor, the ceiling, and a sweep of texels.
	std::vector<cv::Point> texels = { { 465, 270 }, { 525, 210 }, { 650, 260 }, { 900, 220 }, { 300, 450 }, { 100, 40 } };
	for (int k = 0; k < 64; ++k) {
		texels.push_back({ (k * 163) % pano.cols, 8 + (k * 97) % (pano.rows - 16) });
	}
	for (const cv::Point &texel : texels) {
		CAPTURE(texel.x);
		CAPTURE(texel.y);
		const glm::dvec3 d = texel_direction(texel.x, texel.y, pano.cols, pano.rows);
		Hit hit;
		const Color c = room.renderer->radiance(room.scene.panorama_center, d, 0.0, &hit);
		REQUIRE(hit.hit);
		const cv::Vec3f truth = pano.at<cv::Vec3f>(texel.y, texel.x) * float(scale);
		CHECK(c.r == doctest::Approx(truth[0]).epsilon(1e-4));
		CHECK(c.g == doctest::Approx(truth[1]).epsilon(1e-4));
		CHECK(c.b == doctest::Approx(truth[2]).epsilon(1e-4));
	}
}

TEST_CASE("synth: panorama_room's ground-truth cubemap at the centre is the panorama") {
	if (skip_without_panorama()) {
		return;
	}
	// Both panoramas of ../shared/data/hdri where present: --hdri picks either.
	for (const std::string file : { "lebombo_1k.hdr", "studio_small_03_1k.hdr" }) {
		CAPTURE(file);
		const std::string path = std::string(ROOMPROBE_SHARED_DATA) + "/hdri/" + file;
		const PanoramaLoadResult panorama = load_panorama(path);
		if (!panorama.ok) {
			MESSAGE("skipped " << file << ": " << panorama.error);
			continue;
		}
		SceneOptions options;
		options.panorama_path = path;
		const SceneResult scene = make_scene("panorama_room", options);
		REQUIRE_MESSAGE(scene.ok, scene.error);
		const SynthRenderer renderer(scene.scene);
		REQUIRE(renderer.ok());
		const double scale = scene.scene.panorama_scale;
		CHECK(scale == doctest::Approx(panorama_exposure_scale(*panorama.panorama)));
		const int size = 32;
		const auto faces = render_cubemap(renderer, scene.scene.probe_position, 1.0, size);
		int off = 0;
		for (int f = 0; f < 6; ++f) {
			for (int y = 0; y < size; ++y) {
				for (int x = 0; x < size; ++x) {
					const Color truth = float(scale) * panorama.panorama->lookup(cubemap_direction(f, x, y, size));
					const cv::Vec3f c = faces[f].at<cv::Vec3f>(y, x);
					for (int k = 0; k < 3; ++k) {
						off += std::abs(c[k] - truth[k]) > 1e-4 * truth[k] + 1e-7;
					}
				}
			}
		}
		CHECK(off == 0);
	}
}

TEST_CASE("synth: panorama_room's wall pixels are the panorama from the centre, in 8-bit sRGB at its exposure") {
	if (skip_without_panorama()) {
		return;
	}
	const panorama_room_frames::Room &room = panorama_room_frames::room();
	const PinholeParams camera = panorama_room_frames::camera(320, 240);
	panorama_room_frames::FrameOptions options;
	options.noisy = false;
	for (int index : { 0, 75, 150, 220 }) {
		CAPTURE(index);
		const panorama_room_frames::Frame frame = panorama_room_frames::render_frame(index, options);
		const glm::dmat3 rotation = glm::mat3_cast(frame.world_from_camera.rotation);
		const glm::dvec3 origin = frame.world_from_camera.translation;
		int wrong_colour = 0, wrong_depth = 0, pixels = 0;
		for (int y = 0; y < camera.height; ++y) {
			for (int x = 0; x < camera.width; ++x) {
				// The pixel's ray meets wall 0, the plane z = 0 (every pixel: the camera faces it).
				const glm::dvec3 ray_camera = unproject_pinhole(camera, glm::dvec2(x, y));
				const glm::dvec3 ray = rotation * ray_camera;
				if (!(ray.z < 0.0)) {
					FAIL("a pixel's ray does not meet wall 0: " << x << ", " << y);
				}
				const double t = -origin.z / ray.z; // ray_camera.z = 1: t is the depth z
				const glm::dvec3 point = origin + t * ray;
				const Color truth = float(room.scene.panorama_scale) * room.scene.panorama->lookup(point - room.scene.panorama_center);
				const cv::Vec3b rgb = frame.rgb.at<cv::Vec3b>(y, x);
				// 8-bit sRGB quantisation: the code of the true value, give or take one where the
				// true value lies on a step.
				bool ok = true;
				for (int k = 0; k < 3; ++k) {
					ok = ok && std::abs(int(rgb[k]) - int(linear_to_srgb8(truth[k]))) <= 1;
				}
				wrong_colour += !ok;
				wrong_depth += !(std::abs(frame.depth_m.at<float>(y, x) - t) < 1e-4);
				++pixels;
			}
		}
		CHECK(pixels == camera.width * camera.height);
		CHECK(wrong_colour == 0);
		CHECK(wrong_depth == 0); // also: no holes in a convex, empty room
	}
}

TEST_CASE("synth: panorama_room's 8-bit frames have texture, neither black nor saturated") {
	if (skip_without_panorama()) {
		return;
	}
	panorama_room_frames::FrameOptions options;
	options.width = 160;
	options.height = 120;
	options.count = 10;
	options.stride = 30;
	for (const panorama_room_frames::Frame &frame : panorama_room_frames::render_frames(options)) {
		CAPTURE(frame.index);
		int saturated = 0, dark = 0;
		std::vector<int> codes;
		for (int y = 0; y < frame.rgb.rows; ++y) {
			for (int x = 0; x < frame.rgb.cols; ++x) {
				const cv::Vec3b c = frame.rgb.at<cv::Vec3b>(y, x);
				saturated += std::max({ c[0], c[1], c[2] }) == 255;
				dark += std::max({ c[0], c[1], c[2] }) < 20;
				codes.push_back(c[1]);
			}
		}
		const double n = double(codes.size());
		std::nth_element(codes.begin(), codes.begin() + codes.size() / 2, codes.end());
		CHECK(codes[codes.size() / 2] > 60); // the median green code
		CHECK(codes[codes.size() / 2] < 220);
		CHECK(dark / n < 0.02);
		CHECK(saturated / n < 0.3); // only the photograph's window saturates
		// Texture: a share of pixels with a clear gradient (the door, lamps, window frame, curtains).
		cv::Mat grey, gx, gy;
		cv::cvtColor(frame.rgb, grey, cv::COLOR_RGB2GRAY);
		cv::Sobel(grey, gx, CV_32F, 1, 0);
		cv::Sobel(grey, gy, CV_32F, 0, 1);
		cv::Mat magnitude;
		cv::magnitude(gx, gy, magnitude);
		CHECK(cv::countNonZero(magnitude > 40.0f) / n > 0.02);
	}
}

TEST_CASE("synth: panorama_room renders deterministically, and the helper's frames are the sensor's") {
	if (skip_without_panorama()) {
		return;
	}
	const panorama_room_frames::Room &room = panorama_room_frames::room();
	panorama_room_frames::FrameOptions options;
	options.width = 160;
	options.height = 120;
	const panorama_room_frames::Frame a = panorama_room_frames::render_frame(40, options);
	const panorama_room_frames::Frame b = panorama_room_frames::render_frame(40, options);
	CHECK(cv::norm(a.rgb, b.rgb, cv::NORM_INF) == 0);
	CHECK(cv::norm(a.depth_m, b.depth_m, cv::NORM_INF) == 0);
	// The helper skips the projector's shadow rays; a full render_rgbd, seeded as write_sequence
	// seeds frame 40, gives the same bytes.
	RgbdOptions full;
	full.noise_seed = mix_seed(1, 0x10000000ULL + 40);
	const RgbdImage image = render_rgbd(*room.renderer, panorama_room_frames::camera(160, 120), 0.001, a.world_from_camera, a.timestamp_s, full);
	CHECK(cv::norm(a.rgb, image.rgb, cv::NORM_INF) == 0);
	cv::Mat depth_mm;
	a.depth_m.convertTo(depth_mm, CV_32F, 1000.0);
	cv::Mat image_mm;
	image.depth.convertTo(image_mm, CV_32F);
	CHECK(cv::norm(depth_mm, image_mm, cv::NORM_INF) < 1e-3);
	// The noise follows the seed; the picture does not.
	options.seed = 2;
	const panorama_room_frames::Frame other = panorama_room_frames::render_frame(40, options);
	CHECK(cv::norm(a.depth_m, other.depth_m, cv::NORM_INF) > 0);
	const panorama_room_frames::Frame same_pose = panorama_room_frames::render_frame(40, options);
	CHECK(cv::norm(other.rgb, same_pose.rgb, cv::NORM_INF) == 0);
}

TEST_CASE("synth: panorama_room's hand-held trajectory sweeps along wall 0, facing it, inside the room") {
	if (skip_without_panorama()) {
		return;
	}
	const Scene &scene = panorama_room_frames::room().scene;
	const SynthRenderer &renderer = *panorama_room_frames::room().renderer;
	const PinholeParams camera = test_rig().rgb;
	for (uint64_t seed : { 1, 2, 3 }) {
		CAPTURE(seed);
		const HandheldTrajectory trajectory = make_handheld_trajectory(scene, seed);
		const HandheldTrajectory same = make_handheld_trajectory(scene, seed);
		const HandheldTrajectory other = make_handheld_trajectory(scene, seed + 10);
		CHECK(trajectory.kind == TrajectoryKind::WallSweep);
		double largest_speed = 0.0, largest_turn = 0.0, min_x = 1e9, max_x = -1e9;
		int off_wall_rays = 0, rays = 0;
		bool differs = false;
		Pose previous = trajectory.world_from_rgb(0.0);
		for (int i = 0; i < 300; ++i) {
			const double t = i / 30.0;
			const Pose pose = trajectory.world_from_rgb(t);
			const Pose again = same.world_from_rgb(t);
			CHECK(pose.translation == again.translation);
			CHECK(pose.rotation == again.rotation);
			differs = differs || glm::length(other.world_from_rgb(t).translation - pose.translation) > 0.05;
			const glm::dvec3 p = pose.translation;
			// 1 to 2 m from wall 0 (z = 0), well away from the side walls, floor and ceiling.
			CHECK(p.z > 1.2);
			CHECK(p.z < 1.8);
			CHECK(p.x > 1.2);
			CHECK(p.x < 3.8);
			CHECK(p.y > 1.2);
			CHECK(p.y < 1.6);
			min_x = std::min(min_x, p.x);
			max_x = std::max(max_x, p.x);
			// Facing the wall: the optical axis within 8 degrees of -z.
			const glm::dmat3 rotation = glm::mat3_cast(pose.rotation);
			const glm::dvec3 axis = rotation * glm::dvec3(0, 0, 1);
			CHECK(std::acos(-axis.z) < 8.0 * PI / 180.0);
			// The depth camera sees one plane: rays over the whole image all meet wall 0.
			for (int v = 0; v <= 6; ++v) {
				for (int u = 0; u <= 8; ++u) {
					const glm::dvec2 pixel(u * (camera.width - 1) / 8.0, v * (camera.height - 1) / 6.0);
					const Hit hit = renderer.intersect(p, rotation * unproject_pinhole(camera, pixel));
					off_wall_rays += !(hit.hit && std::abs(hit.point.z) < 1e-4);
					++rays;
				}
			}
			// Hand speeds.
			largest_speed = std::max(largest_speed, glm::length(pose.translation - previous.translation) * 30.0);
			largest_turn = std::max(largest_turn, angle_between(pose.rotation, previous.rotation) * 30.0 * 180.0 / PI);
			previous = pose;
		}
		CHECK(off_wall_rays == 0);
		CHECK(rays == 300 * 63);
		CHECK(differs);
		// Sideways: most of the sweep's 1.8 m within 10 s; forward and back: the distance varies.
		CHECK(max_x - min_x > 1.5);
		CHECK(largest_speed < 1.0);
		CHECK(largest_speed > 0.3);
		CHECK(largest_turn < 45.0);
	}
}

TEST_CASE("synth: panorama_room frames: sizes, timestamps and true poses") {
	if (skip_without_panorama()) {
		return;
	}
	const PinholeParams half = panorama_room_frames::camera(320, 240);
	CHECK(half.fx == 262.5);
	CHECK(half.cx == 159.5);
	CHECK(half.cy == 119.5);
	const PinholeParams full = panorama_room_frames::camera(640, 480);
	CHECK(full.fx == test_rig().rgb.fx);
	CHECK(full.cx == test_rig().rgb.cx);
	for (int width : { 320, 640 }) {
		CAPTURE(width);
		panorama_room_frames::FrameOptions options;
		options.width = width;
		options.height = width * 3 / 4;
		options.first = 12;
		options.count = 2;
		options.stride = 5;
		const std::vector<panorama_room_frames::Frame> frames = panorama_room_frames::render_frames(options);
		REQUIRE(frames.size() == 2);
		for (size_t k = 0; k < frames.size(); ++k) {
			const panorama_room_frames::Frame &f = frames[k];
			CHECK(f.index == 12 + 5 * int(k));
			CHECK(f.timestamp_s == doctest::Approx(f.index / 30.0));
			const Pose truth = panorama_room_frames::pose_at(f.timestamp_s);
			CHECK(f.world_from_camera.translation == truth.translation);
			CHECK(f.world_from_camera.rotation == truth.rotation);
			CHECK(f.rgb.type() == CV_8UC3);
			CHECK(f.rgb.cols == options.width);
			CHECK(f.rgb.rows == options.height);
			CHECK(f.depth_m.type() == CV_32FC1);
			// The sensor's noise: within 4 sigma of the truth, in 1 mm steps, everywhere.
			int far = 0;
			for (int y = 0; y < f.depth_m.rows; ++y) {
				for (int x = 0; x < f.depth_m.cols; ++x) {
					const double z = f.depth_true_m.at<float>(y, x), measured = f.depth_m.at<float>(y, x);
					far += !(std::abs(measured - z) < 4.0 * kinect_depth_sigma_m(z) + 0.0005);
				}
			}
			CHECK(far < f.depth_m.rows * f.depth_m.cols / 1000);
		}
	}
}

TEST_CASE("synth: panorama_room needs its panorama") {
	const SceneResult none = make_scene("panorama_room", SceneOptions());
	CHECK_FALSE(none.ok);
	CHECK(none.error.find("needs a panorama") != std::string::npos);
	SceneOptions options;
	options.panorama_path = "/nonexistent/panorama.hdr";
	const SceneResult missing = make_scene("panorama_room", options);
	CHECK_FALSE(missing.ok);
	CHECK(missing.error.find("/nonexistent/panorama.hdr") != std::string::npos);
	const std::vector<std::string> names = scene_names();
	CHECK(std::find(names.begin(), names.end(), "panorama_room") != names.end());
}
