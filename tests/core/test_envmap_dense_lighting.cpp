// envmap/dense_render.h's DenseLighting (issue #42): the dense colours take the lighting change
// per block, by when their surface was last fused; a block fused after the change shows none.

#include <io/opencv.h>

#include "envmap/dense_render.h"
#include "slam/tsdf_volume.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <numbers>

using namespace roomprobe;

namespace {

PinholeIntrinsics wall_camera() {
	PinholeIntrinsics camera;
	camera.width = 64;
	camera.height = 48;
	camera.fx = camera.fy = 40.0f;
	camera.cx = 31.5f;
	camera.cy = 23.5f;
	return camera;
}

// A grey wall (p_grey, 8-bit) 1 m in front of a camera at the origin, looking along +Z turned
// by p_turn_about_y_rad about +Y.
void fuse_wall(TsdfVolume *r_volume, double p_turn_about_y_rad, int p_frames, int p_grey = 128) {
	const PinholeIntrinsics camera = wall_camera();
	const cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(1.0f));
	const cv::Mat rgb(camera.height, camera.width, CV_8UC3, cv::Scalar(p_grey, p_grey, p_grey));
	Pose pose;
	pose.rotation = glm::angleAxis(p_turn_about_y_rad, glm::dvec3(0.0, 1.0, 0.0));
	for (int i = 0; i < p_frames; i++) {
		r_volume->integrate(depth, rgb, camera, pose);
	}
}

LightingChange gain_of(float p_gain) {
	LightingChange change;
	change.valid = true;
	change.gain = cv::Vec3f(p_gain, p_gain, p_gain);
	return change;
}

constexpr int FACE_POSITIVE_X = 0, FACE_POSITIVE_Z = 4;

} // namespace

TEST_CASE("dense lighting: epochs map each frame to the change its colours have not seen") {
	DenseLighting lighting;
	const LightingChange none, doubled = gain_of(2.0f), tripled = gain_of(3.0f);
	CHECK(lighting.epochs(doubled).since.size() == 1); // nothing recorded: colours of the lighting now
	CHECK(lighting.epochs(doubled).since[0].gain[0] == doctest::Approx(1.0));
	lighting.record(5, none); // frames 5.. under no change
	lighting.record(6, gain_of(1.002f)); // within rounding: no new epoch
	lighting.record(9, doubled); // frames 9.. under the doubled light
	lighting.record(12, tripled);
	const DenseLightingEpochs epochs = lighting.epochs(tripled);
	REQUIRE(epochs.since.size() == 3);
	CHECK(epochs.at_frame(1).gain[0] == doctest::Approx(3.0)); // before the first epoch: its change
	CHECK(epochs.at_frame(8).gain[0] == doctest::Approx(3.0));
	CHECK(epochs.at_frame(9).gain[0] == doctest::Approx(1.5));
	CHECK(epochs.at_frame(11).gain[0] == doctest::Approx(1.5));
	CHECK(epochs.at_frame(12).gain[0] == doctest::Approx(1.0));
	CHECK(epochs.at_frame(0).gain[0] == doctest::Approx(1.0)); // no block: the newest
	// The light doubling again after the last fused frame reaches every colour.
	CHECK(lighting.epochs(gain_of(6.0f)).at_frame(12).gain[0] == doctest::Approx(2.0));
	lighting.record(12, gain_of(4.0f)); // the same frames recorded again: the epoch's lighting replaced
	CHECK(lighting.epochs(gain_of(4.0f)).since.size() == 3);
	lighting.reset();
	CHECK(lighting.epochs(tripled).since[0].gain[0] == doctest::Approx(1.0));
}

TEST_CASE("dense lighting: a wall fused before the light doubled shows it doubled, one fused after does not") {
	TsdfVolume volume;
	DenseLighting lighting;
	fuse_wall(&volume, 0.0, 3); // +Z wall, under the old light
	lighting.record(volume.frame_count(), LightingChange());
	const LightingChange doubled = gain_of(2.0f);
	fuse_wall(&volume, 0.5 * std::numbers::pi, 3); // +X wall: the light doubled before these frames
	lighting.record(volume.frame_count() - 2, doubled);
	Cubemap map = make_cubemap(16);
	const DenseRenderStats stats = lighting.render_over(volume, doubled, glm::dvec3(0.0), DenseRenderOptions(), &map);
	REQUIRE(stats.texels_covered > 0);
	const float grey = 128.0f / 255.0f;
	const cv::Vec3f z_wall = map.faces[FACE_POSITIVE_Z].at<cv::Vec3f>(8, 8);
	const cv::Vec3f x_wall = map.faces[FACE_POSITIVE_X].at<cv::Vec3f>(8, 8);
	MESSAGE("+Z wall ", z_wall[0], ", +X wall ", x_wall[0]);
	// Fused 8-bit grey read back trilinearly: within one step of 128.
	CHECK(z_wall[0] == doctest::Approx(2.0f * grey).epsilon(0.01));
	CHECK(x_wall[0] == doctest::Approx(grey).epsilon(0.01));
	// The rule before issue #42: one change for every colour, none since the last fused frame.
	DenseRenderOptions single;
	single.lighting = DenseLightingEpochs::uniform(LightingChange());
	Cubemap old_rule = make_cubemap(16);
	render_dense_over(volume, glm::dvec3(0.0), single, &old_rule);
	CHECK(old_rule.faces[FACE_POSITIVE_Z].at<cv::Vec3f>(8, 8)[0] == doctest::Approx(grey).epsilon(0.01));
}

TEST_CASE("dense lighting: a wall fused across the switch takes the change that its running mean of colours needs") {
	// Two frames at 100 under the old light, then two at 200 under the doubled one: the voxels'
	// mean is 150, and the light now shows 200.
	TsdfVolume volume;
	DenseLighting lighting;
	fuse_wall(&volume, 0.0, 2, 100);
	lighting.record(volume.frame_count(), LightingChange());
	const LightingChange doubled = gain_of(2.0f);
	fuse_wall(&volume, 0.0, 2, 200);
	lighting.record(volume.frame_count() - 1, doubled);
	const TsdfSurfaceFrames frames = volume.surface_frames(glm::vec3(0.0f, 0.0f, 1.0f));
	REQUIRE(frames.count == 4);
	const LightingChange change = lighting.epochs(doubled).for_block(frames, glm::vec3(0.0f, 0.0f, 1.0f), volume.options().max_color_weight);
	CHECK(change.gain[0] == doctest::Approx(4.0 / 3.0).epsilon(1e-5));
	Cubemap map = make_cubemap(16);
	lighting.render_over(volume, doubled, glm::dvec3(0.0), DenseRenderOptions(), &map);
	const cv::Vec3f wall = map.faces[FACE_POSITIVE_Z].at<cv::Vec3f>(8, 8);
	MESSAGE("the wall now ", wall[0] * 255.0f, " of 255");
	CHECK(wall[0] == doctest::Approx(200.0f / 255.0f).epsilon(0.01));
	// Past the colour weight's cap (8) each new frame takes a ninth of the mean: ten more frames
	// at 200 leave the old light's 100s a share of the mean that the map must still lift.
	fuse_wall(&volume, 0.0, 10, 200);
	REQUIRE(volume.surface_frames(glm::vec3(0.0f, 0.0f, 1.0f)).count == 14);
	Cubemap later = make_cubemap(16);
	lighting.render_over(volume, doubled, glm::dvec3(0.0), DenseRenderOptions(), &later);
	const float lifted = later.faces[FACE_POSITIVE_Z].at<cv::Vec3f>(8, 8)[0];
	MESSAGE("ten frames later the wall ", lifted * 255.0f, " of 255");
	CHECK(lifted == doctest::Approx(200.0f / 255.0f).epsilon(0.01));
}
