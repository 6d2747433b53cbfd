// Issue #43: a rig without a fisheye (an RGB-D camera alone). The engine takes RGB-D frames as the
// coarse model's views (CoarsePipeline::add_rgb_view), at most every rgb_view_interval_s, in step
// mode and on the coarse worker. The texels are scored against the synthetic room's true radiance,
// as test_coarse_rgb_texture.cpp scores the RGB texturing beside a fisheye.

#include "engine/live_room.h"
#include "pipeline/coarse_pipeline.h"
#include "engine_test_recording.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

namespace roomprobe {

using namespace engine_test;

namespace {

// The recording's true RGB-D poses, for the coarse model's poses (no SLAM: the test is about texels).
Trajectory true_trajectory(const Recording &p_rec) {
	Trajectory truth;
	std::string error;
	for (const RgbdFrame &frame : p_rec.rgbd) {
		REQUIRE(truth.append(TimedPose{ frame.timestamp_s, synth_frames::living_room().trajectory.world_from_rgb(frame.timestamp_s) }, &error));
	}
	return truth;
}

LiveRoomConfig coarse_config(const Recording &p_rec, bool p_fisheye) {
	LiveRoomConfig cfg = live_config(p_rec);
	cfg.dense = false;
	cfg.coarse_poses = PoseSource::GroundTruth;
	cfg.ground_truth = true_trajectory(p_rec);
	cfg.coarse.lighting = false; // the RGB views estimate none: texturing against texturing
	cfg.coarse.rgb_texture = false; // with the fisheye: the paper's, the fisheye alone
	if (!p_fisheye) {
		cfg.rig = rgbd_camera_alone(cfg.rig); // cfg.photometry keeps the RGB camera's response
	}
	return cfg;
}

// The surface's radiance seen from just in front of texel i, where nothing stands against the
// surface (as test_coarse_rgb_texture.cpp); false where something does.
bool true_radiance(const TexelGeometry &p_geometry, size_t p_texel, cv::Vec3f *r_value) {
	synth::Hit hit;
	const double offset = 0.005;
	const synth::Color t = synth_frames::living_room().renderer->radiance(p_geometry.points[p_texel] + offset * p_geometry.normals[p_texel],
			-p_geometry.normals[p_texel], 0.3, &hit);
	*r_value = cv::Vec3f(t.r, t.g, t.b);
	return hit.hit && std::abs(hit.distance - offset) <= 1e-3;
}

double mean_abs_error(const cv::Vec3f &p_a, const cv::Vec3f &p_b) {
	return (std::abs(p_a[0] - p_b[0]) + std::abs(p_a[1] - p_b[1]) + std::abs(p_a[2] - p_b[2])) / 3.0;
}

} // namespace

TEST_CASE("engine: without a fisheye the RGB camera textures the coarse model, closer to the truth than the fisheye's fill where it never looked") {
	const Recording &rec = recording();
	LiveRoom rgb_only, with_fisheye;
	REQUIRE(rgb_only.configure(coarse_config(rec, false)) == "");
	REQUIRE(with_fisheye.configure(coarse_config(rec, true)) == "");
	for (const Event &event : rec.events) {
		push_event(with_fisheye, rec, event);
		if (!event.fisheye) {
			rgb_only.push_rgbd(rec.rgbd[event.index]);
		}
	}
	rgb_only.finish();
	with_fisheye.finish();
	const LiveRoomStats stats = rgb_only.stats();
	// A view at the first frame, then one per rgb_view_interval_s (1/12 s) of the 0.6 s at 30 Hz.
	const double span_s = rec.rgbd.back().timestamp_s - rec.rgbd.front().timestamp_s;
	CHECK(stats.rgb_views_integrated >= uint64_t(std::floor(span_s * 12.0 * 0.5)));
	CHECK(stats.rgb_views_integrated <= uint64_t(std::ceil(span_s * 12.0)) + 1);
	CHECK(stats.fisheye_integrated == 0);
	CHECK(stats.stage_errors == 0);

	const CoarsePipeline *coarse = rgb_only.coarse_model();
	const CoarsePipeline *fisheye = with_fisheye.coarse_model();
	REQUIRE(coarse != nullptr);
	REQUIRE(fisheye != nullptr);
	CHECK(coarse->rgb_only());
	CHECK_FALSE(fisheye->rgb_only());
	const TexelGeometry geometry = make_texel_geometry(coarse->mesh());
	double rgb_error = 0.0, fill_error = 0.0, rgb_shared_error = 0.0, fisheye_shared_error = 0.0;
	size_t unseen = 0, shared = 0, observed = 0;
	for (int y = 0; y < geometry.height; y++) {
		for (int x = 0; x < geometry.width; x++) {
			const size_t i = size_t(y) * size_t(geometry.width) + size_t(x);
			cv::Vec3f truth;
			if (geometry.charts[i] < 0 || !coarse->texture().observed.at<uint8_t>(y, x) || !true_radiance(geometry, i, &truth)) {
				continue;
			}
			observed++;
			const double e_rgb = mean_abs_error(coarse->texture().color.at<cv::Vec3f>(y, x), truth);
			if (fisheye->texture().observed.at<uint8_t>(y, x)) {
				shared++;
				rgb_shared_error += e_rgb;
				fisheye_shared_error += mean_abs_error(fisheye->texture().color.at<cv::Vec3f>(y, x), truth);
			} else {
				unseen++;
				rgb_error += e_rgb;
				fill_error += mean_abs_error(fisheye->completed_color().at<cv::Vec3f>(y, x), truth);
			}
		}
	}
	MESSAGE(observed, " texels from ", stats.rgb_views_integrated, " RGB views; ", unseen, " the fisheye never saw: RGB error ", rgb_error / double(unseen),
			", the fisheye pipeline's fill ", fill_error / double(unseen), "; ", shared, " both saw: RGB ", rgb_shared_error / double(shared), ", fisheye ",
			fisheye_shared_error / double(shared));
	REQUIRE(unseen >= 100);
	CHECK(rgb_error < fill_error);

	// The map at the probe is the room's, not black: its SH DC term within the fisheye model's.
	const int probe = rgb_only.add_probe(rec.probe, 16);
	const int probe_fisheye = with_fisheye.add_probe(rec.probe, 16);
	REQUIRE(rgb_only.render_probe(probe));
	REQUIRE(with_fisheye.render_probe(probe_fisheye));
	const glm::vec3 dc = rgb_only.probe_map(probe)->sh[0], dc_fisheye = with_fisheye.probe_map(probe_fisheye)->sh[0];
	MESSAGE("SH DC: RGB only ", dc.x, " ", dc.y, " ", dc.z, "; with the fisheye ", dc_fisheye.x, " ", dc_fisheye.y, " ", dc_fisheye.z);
	for (int c = 0; c < 3; c++) {
		CHECK(dc[c] > 0.0f);
	}

	// A fisheye frame pushed to it anyway is refused at the door, named.
	rgb_only.push_fisheye(rec.fisheye.front());
	CHECK(rgb_only.stats().stage_errors == 1);
	CHECK(rgb_only.stats().last_error.find("fisheye frame: the rig has no fisheye") != std::string::npos);
}

// The lighting change from RGB views alone (§4.6 with the RGB camera's pairs): a second view 1.3
// times brighter (without a response curve, value / 255 is linear, so scaled 8-bit values are an
// exact gain up to their rounding) gives a gain of 1.3, which reaches the texels only the first
// view saw.
TEST_CASE("coarse pipeline: without a fisheye, RGB views seen again estimate the lighting change and carry it to the texels they did not see") {
	const Recording &rec = recording();
	CoarsePipelineOptions options;
	options.inpaint = false;
	options.lighting = true;
	options.lighting_model = LightingModel::GAIN_ROBUST;
	CoarsePipeline lit(options), unlit(options);
	const Rig rig = rgbd_camera_alone(rec.rig);
	REQUIRE(lit.configure(rig, rec.floorplan) == "");
	REQUIRE(unlit.configure(rig, rec.floorplan) == "");
	REQUIRE(lit.rgb_only());
	const RgbdFrame &first = rec.rgbd.front(), &last = rec.rgbd.back();
	const auto pose = [](const RgbdFrame &p_frame) { return synth_frames::living_room().trajectory.world_from_rgb(p_frame.timestamp_s); };
	RgbdFrame brighter = last;
	// Values whose scaled value would clip are left as they were (the estimate is robust to them).
	brighter.rgb = last.rgb.clone();
	brighter.rgb.forEach<cv::Vec3b>([](cv::Vec3b &p_pixel, const int *) {
		if (std::max({ p_pixel[0], p_pixel[1], p_pixel[2] }) <= 190) {
			for (int c = 0; c < 3; c++) {
				p_pixel[c] = uint8_t(std::lround(p_pixel[c] * 1.3));
			}
		}
	});
	CHECK_FALSE(lit.add_rgb_view(first, rig.rgb, pose(first), nullptr).lighting.valid); // nothing seen before
	unlit.add_rgb_view(first, rig.rgb, pose(first), nullptr);
	const CoarseFrameStats second = lit.add_rgb_view(brighter, rig.rgb, pose(last), nullptr);
	REQUIRE(second.lighting.valid);
	MESSAGE("gain ", second.lighting.gain[0], " ", second.lighting.gain[1], " ", second.lighting.gain[2]);
	for (int c = 0; c < 3; c++) {
		// 8-bit rounding: half a code in values of 40 and more is 1.3 % at most, and the median of many pairs much less.
		CHECK(second.lighting.gain[c] == doctest::Approx(1.3).epsilon(0.02));
	}
	// A texel the first view saw and the second did not update now holds its first value times the gain.
	int carried = 0, checked = 0;
	for (int y = 0; y < lit.texture().color.rows; y++) {
		for (int x = 0; x < lit.texture().color.cols; x++) {
			if (!unlit.texture().observed.at<uint8_t>(y, x) || lit.texture().updated.at<uint8_t>(y, x)) {
				continue;
			}
			const cv::Vec3f before = unlit.texture().color.at<cv::Vec3f>(y, x), after = lit.texture().color.at<cv::Vec3f>(y, x);
			checked++;
			carried += std::abs(after[1] - second.lighting.gain[1] * before[1]) <= 1e-5f + 1e-5f * std::abs(after[1]);
		}
	}
	MESSAGE(checked, " texels the first view saw and the second did not update, ", carried, " of them carried by the gain");
	REQUIRE(checked > 100);
	CHECK(carried == checked);
}

TEST_CASE("engine: without a fisheye the coarse worker takes the views while running; finish() takes the last one") {
	const Recording &rec = recording();
	LiveRoom engine;
	REQUIRE(engine.configure(coarse_config(rec, false)) == "");
	REQUIRE(engine.start());
	for (const RgbdFrame &frame : rec.rgbd) {
		engine.push_rgbd(frame);
		std::this_thread::sleep_for(std::chrono::milliseconds(5));
	}
	engine.finish();
	const LiveRoomStats stats = engine.stats();
	engine.stop();
	CHECK(stats.rgb_views_integrated >= 1);
	CHECK(stats.stage_errors == 0);
	const auto snapshot = engine.coarse_snapshot();
	REQUIRE(snapshot != nullptr);
	CHECK(cv::countNonZero(snapshot->atlas.reshape(1) > 0.0f) > 0);
}

} // namespace roomprobe
