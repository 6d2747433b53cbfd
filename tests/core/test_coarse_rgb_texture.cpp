// coarse/rgb_texture_update.h: the RGB camera textures what the fisheye never saw, where its
// registered depth says it sees the texel itself, keeping the best view, never over the fisheye.

#include "io/opencv.h"
#include "coarse/coarse_texture.h"
#include "coarse/rgb_texture_update.h"
#include "coarse/texture_update.h"
#include "room/reference_rooms.h"
#include "room/room_mesh.h"
#include "pipeline/coarse_pipeline.h"
#include "recording/recording_reader.h"
#include "rig/fisheye_pose.h"
#include "rig/photometry.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <filesystem>
#include <unistd.h>

using namespace roomprobe;

namespace {

// An RGB camera at height p_height above floor point (2.5, 2.0) of the living room, looking
// straight down: camera x = world +X, y = world +Z, z = world -Y.
Pose downward_camera(double p_height) {
	const glm::dmat3 world_from_camera(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, -1, 0));
	Pose pose;
	pose.rotation = glm::quat_cast(world_from_camera);
	pose.translation = glm::dvec3(2.5, p_height, 2.0);
	return pose;
}

PinholeParams small_camera() {
	PinholeParams camera;
	camera.width = 160;
	camera.height = 120;
	camera.fx = camera.fy = 100.0;
	camera.cx = 80.0;
	camera.cy = 60.0;
	return camera;
}

// The floor seen from p_height in grey p_grey, with a box (0.7 m nearer, grey 30) over pixels
// [60, 100) x [40, 80).
void floor_frame(double p_height, int p_grey, cv::Mat *r_rgb, cv::Mat *r_depth) {
	*r_rgb = cv::Mat(120, 160, CV_8UC3, cv::Scalar::all(p_grey));
	*r_depth = cv::Mat(120, 160, CV_32FC1, cv::Scalar(p_height));
	const cv::Rect box(60, 40, 40, 40);
	(*r_rgb)(box).setTo(cv::Scalar::all(30));
	(*r_depth)(box).setTo(cv::Scalar(p_height - 0.7));
}

// The pixel of floor point (x, 0, z) in the camera at p_height (no distortion: exact).
cv::Point2d floor_pixel(const glm::dvec3 &p_point, double p_height) {
	return cv::Point2d(100.0 * (p_point.x - 2.5) / p_height + 80.0, 100.0 * (p_point.z - 2.0) / p_height + 60.0);
}

} // namespace

TEST_CASE("coarse rgb texture: the floor the fisheye never saw comes from the RGB camera, not through the box on it") {
	const RoomMeshResult built = build_room_mesh(living_room());
	REQUIRE(built.ok);
	const TexelGeometry geometry = make_texel_geometry(built.mesh);
	CoarseTexture texture = make_coarse_texture(built.mesh);
	// One floor texel in view already holds a fisheye observation.
	size_t fisheye_texel = 0;
	for (size_t i = 0; i < geometry.points.size(); i++) {
		if (geometry.charts[i] >= 0 && geometry.normals[i].y > 0.9 && std::abs(geometry.points[i].x - 2.0) < 0.011 && std::abs(geometry.points[i].z - 1.6) < 0.011) {
			fisheye_texel = i;
		}
	}
	REQUIRE(fisheye_texel > 0);
	const int fx = int(fisheye_texel % size_t(geometry.width)), fy = int(fisheye_texel / size_t(geometry.width));
	texture.quality.at<float>(fy, fx) = 1.0f;
	texture.observed.at<uint8_t>(fy, fx) = 255;
	texture.color.at<cv::Vec3f>(fy, fx) = cv::Vec3f(0.9f, 0.9f, 0.9f);

	cv::Mat rgb, depth;
	floor_frame(1.5, 100, &rgb, &depth);
	const RgbTextureStats stats = update_coarse_texture_from_rgb(geometry, small_camera(), downward_camera(1.5), rgb, depth, nullptr, &texture);
	size_t expected_in = 0, taken = 0, wrong = 0, under_box = 0, under_box_taken = 0;
	for (size_t i = 0; i < geometry.points.size(); i++) {
		if (geometry.charts[i] < 0 || !(geometry.normals[i].y > 0.9) || i == fisheye_texel) {
			continue;
		}
		const cv::Point2d px = floor_pixel(geometry.points[i], 1.5);
		const int x = int(i % size_t(geometry.width)), y = int(i / size_t(geometry.width));
		const bool observed = texture.observed.at<uint8_t>(y, x) != 0;
		if (px.x > 2.0 && px.x < 157.0 && px.y > 2.0 && px.y < 117.0 && !(px.x > 58.0 && px.x < 102.0 && px.y > 38.0 && px.y < 82.0)) {
			expected_in++;
			taken += observed ? 1 : 0;
			wrong += observed && std::abs(texture.color.at<cv::Vec3f>(y, x)[0] - 100.0f / 255.0f) > 1e-5f ? 1 : 0;
		} else if (px.x > 61.0 && px.x < 99.0 && px.y > 41.0 && px.y < 79.0) {
			under_box++;
			under_box_taken += observed ? 1 : 0;
		}
	}
	REQUIRE(expected_in > 1000);
	REQUIRE(under_box > 100);
	CHECK(taken == expected_in); // every floor texel in view, outside the box
	CHECK(wrong == 0); // with the camera's value (no lut: value / 255)
	CHECK(under_box_taken == 0); // the depth says the box is in front: not the floor's colour
	CHECK(stats.texels_updated >= taken);
	CHECK(texture.color.at<cv::Vec3f>(fy, fx)[0] == 0.9f); // the fisheye's stays
	CHECK(texture.rgb_quality.at<float>(fy, fx) == 0.0f);

	// A farther view (worse) does not replace the kept one; a nearer one does.
	floor_frame(2.3, 200, &rgb, &depth);
	update_coarse_texture_from_rgb(geometry, small_camera(), downward_camera(2.3), rgb, depth, nullptr, &texture);
	size_t near_centre = 0;
	for (size_t i = 0; i < geometry.points.size(); i++) {
		if (geometry.charts[i] >= 0 && geometry.normals[i].y > 0.9 && std::abs(geometry.points[i].x - 2.0) < 0.011 && std::abs(geometry.points[i].z - 2.0) < 0.011) {
			near_centre = i;
		}
	}
	REQUIRE(near_centre > 0);
	const int nx = int(near_centre % size_t(geometry.width)), ny = int(near_centre / size_t(geometry.width));
	CHECK(texture.color.at<cv::Vec3f>(ny, nx)[0] == doctest::Approx(100.0f / 255.0f));
	floor_frame(1.0, 50, &rgb, &depth);
	update_coarse_texture_from_rgb(geometry, small_camera(), downward_camera(1.0), rgb, depth, nullptr, &texture);
	CHECK(texture.color.at<cv::Vec3f>(ny, nx)[0] == doctest::Approx(50.0f / 255.0f));
	// Clipped pixels are never taken.
	CoarseTexture fresh = make_coarse_texture(built.mesh);
	floor_frame(1.5, 255, &rgb, &depth);
	CHECK(update_coarse_texture_from_rgb(geometry, small_camera(), downward_camera(1.5), rgb, depth, nullptr, &fresh).texels_updated == 0);
}

// On a rendered two-rooms sweep (1 s, true poses), texel by texel against the scene's own
// radiance: what the RGB camera gives the texels the fisheye never saw is far closer to the truth
// than what the inpainting (§4.5) would have put there, and as close as the fisheye's own texels.
TEST_CASE("coarse rgb texture: on a rendered sweep, RGB texels beat the inpainting they replace") {
	const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("roomprobe_rgb_texture_" + std::to_string(::getpid()));
	std::filesystem::remove_all(folder);
	synth::SceneOptions scene_options;
	scene_options.duration_s = 1.0;
	const synth::SceneResult scene = synth::make_scene("two_rooms", scene_options);
	REQUIRE_MESSAGE(scene.ok, scene.error);
	synth::SequenceOptions sequence;
	sequence.duration_s = 1.0;
	sequence.seed = 3;
	sequence.cubemap_face_size = 8;
	sequence.calibration_views = false;
	Rig rig = test_rig();
	REQUIRE(synth::write_sequence(folder.string(), rig, scene.scene, sequence).ok);
	RecordingReader reader;
	REQUIRE(reader.open(folder.string()).ok);
	RigPhotometry photometry;
	std::string error;
	REQUIRE(read_recording_photometry(folder.string(), reader.get_rig().photometry, &photometry, &error));
	REQUIRE(photometry.known);
	const ResponseCurve lut = rgb_radiance_lut(photometry);
	FisheyeLinearizer linearizer;
	linearizer.configure(photometry, reader.get_rig().fisheye);
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	// One pipeline with both cameras, one with the fisheye alone (inpainted), no lighting change.
	CoarsePipelineOptions options;
	options.lighting = false;
	options.rgb_texture = true;
	CoarsePipeline both(options), fisheye_only(options);
	REQUIRE(both.configure(reader.get_rig(), reader.get_room().floorplan) == "");
	REQUIRE(fisheye_only.configure(reader.get_rig(), reader.get_room().floorplan) == "");
	for (const PlaybackEvent &event : reader.get_events()) {
		Pose pose;
		if (event.stream == RecordingStream::Rgbd) {
			const RgbdFrameResult frame = reader.read_rgbd(event.index);
			REQUIRE(frame.ok);
			REQUIRE(truth.pose_at(frame.frame.timestamp_s, &pose, &error));
			both.add_rgb_frame(frame.frame, reader.get_rig().rgb, pose, &lut);
			continue;
		}
		const FisheyeFrameResult frame = reader.read_fisheye(event.index);
		REQUIRE(frame.ok);
		REQUIRE(fisheye_pose_at(truth, reader.get_rig(), frame.frame.timestamp_s, &pose, &error));
		const LinearFrame linear = linearizer.linearise(frame.frame.image, exposure_ratio(photometry.fisheye, frame.frame.capture.exposure_us, frame.frame.capture.gain));
		FisheyeFrame linear_frame = frame.frame;
		linear_frame.image = linear.radiance;
		linear_frame.saturated = linear.saturated;
		both.add_fisheye_frame(linear_frame, pose);
		fisheye_only.add_fisheye_frame(linear_frame, pose);
	}
	const synth::SynthRenderer renderer(scene.scene);
	const TexelGeometry geometry = make_texel_geometry(both.mesh());
	const CoarseTexture &texture = both.texture();
	double rgb_error = 0.0, inpaint_error = 0.0, fisheye_error = 0.0;
	size_t rgb_texels = 0, fisheye_texels = 0;
	for (int y = 0; y < geometry.height; y++) {
		for (int x = 0; x < geometry.width; x++) {
			const size_t i = size_t(y) * geometry.width + x;
			if (geometry.charts[i] < 0 || !texture.observed.at<uint8_t>(y, x) || texture.saturated.at<uint8_t>(y, x)) {
				continue;
			}
			// The truth: the surface's radiance seen from just in front of it (Lambertian), where
			// nothing stands against the surface.
			synth::Hit hit;
			const double offset = 0.005;
			const synth::Color t = renderer.radiance(geometry.points[i] + offset * geometry.normals[i], -geometry.normals[i], 0.0, &hit);
			if (!hit.hit || std::abs(hit.distance - offset) > 1e-3) {
				continue;
			}
			const float value[3] = { t.r, t.g, t.b };
			const cv::Vec3f held = texture.color.at<cv::Vec3f>(y, x), inpainted = fisheye_only.completed_color().at<cv::Vec3f>(y, x);
			double e_held = 0.0, e_inpainted = 0.0;
			for (int c = 0; c < 3; c++) {
				e_held += std::abs(held[c] - value[c]) / 3.0;
				e_inpainted += std::abs(inpainted[c] - value[c]) / 3.0;
			}
			if (texture.rgb_quality.at<float>(y, x) > 0.0f && texture.quality.at<float>(y, x) == 0.0f) {
				rgb_error += e_held;
				inpaint_error += e_inpainted;
				rgb_texels++;
			} else if (texture.quality.at<float>(y, x) > 0.0f) {
				fisheye_error += e_held;
				fisheye_texels++;
			}
		}
	}
	std::filesystem::remove_all(folder);
	REQUIRE(rgb_texels > 1000);
	rgb_error /= double(rgb_texels);
	inpaint_error /= double(rgb_texels);
	fisheye_error /= double(fisheye_texels);
	MESSAGE("texels only the RGB camera saw: " << rgb_texels << ", mean absolute error " << rgb_error << " (the inpainting there: " << inpaint_error
											   << "); the fisheye's texels: " << fisheye_error);
	CHECK(rgb_error < 0.5 * inpaint_error);
	CHECK(rgb_error < 1.5 * fisheye_error);
}
