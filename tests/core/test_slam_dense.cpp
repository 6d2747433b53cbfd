// slam/dense_slam.h: frame-to-model tracking and fusion end to end on the synthetic living room,
// and what happens when tracking is lost; envmap/dense_render.h: the dense model in a probe's map.

#include <io/opencv.h>

#include "envmap/coarse_render.h"
#include "envmap/dense_render.h"
#include "room/room_mesh.h"
#include "slam/dense_slam.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>

using namespace roomprobe;
using namespace synth_frames;

namespace {

constexpr double FRAME_S = 1.0 / 30.0;

RgbdFrame rgbd_at(double p_t, bool p_noisy = true) {
	return rgbd_frame(render_living_room(living_room().trajectory.world_from_rgb(p_t), p_t, p_noisy, uint64_t(p_t * 1000.0) + 3), p_t);
}

// DenseSlam is not movable (it holds its volume's lock): configured in place.
void start_slam(DenseSlam *r_slam, double p_t0) {
	REQUIRE(r_slam->configure(half_camera(), living_room().trajectory.world_from_rgb(p_t0)) == "");
}

} // namespace

TEST_CASE("dense SLAM: one second of the living room tracked frame to model, ATE under 1 cm") {
	DenseSlam slam;
	REQUIRE(slam.configure(half_camera(), living_room().trajectory.world_from_rgb(0.0)) == "");
	double sum_sq = 0.0;
	int tracked = 0;
	for (int i = 0; i < 30; i++) {
		const double t = i * FRAME_S;
		const DenseSlamFrame out = slam.process(rgbd_at(t));
		REQUIRE_MESSAGE(out.tracking.state == TrackingState::Good, "frame ", i, ": ", out.tracking.reason);
		CHECK(out.integrated);
		const glm::dvec3 error = slam.pose().translation - living_room().trajectory.world_from_rgb(t).translation;
		sum_sq += glm::dot(error, error);
		tracked++;
	}
	const double ate_m = std::sqrt(sum_sq / tracked);
	MESSAGE("ATE RMSE over 1 s at 320x240, noisy depth: ", ate_m * 1000.0, " mm");
	CHECK(ate_m < 0.01);
	CHECK(slam.integrated_count() == 30);
	CHECK(slam.volume().stats().allocated_blocks > 100);
	// The model's mesh exists and lies in the room (5 m x 4 m x 2.5 m).
	IncrementalMesher mesher;
	mesher.update(slam.copy_changed_blocks());
	const TriangleMesh mesh = mesher.mesh();
	REQUIRE(!mesh.vertices.empty());
	for (size_t v = 0; v < mesh.vertices.size(); v += 97) {
		CHECK(mesh.vertices[v].x > -0.1f);
		CHECK(mesh.vertices[v].x < 5.1f);
		CHECK(mesh.vertices[v].y > -0.1f);
		CHECK(mesh.vertices[v].y < 2.6f);
	}
}

TEST_CASE("dense SLAM: a frame of zeros is lost, holds the pose, fuses nothing; tracking resumes") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 3; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	const Pose held = slam.pose();
	const size_t fused = slam.integrated_count();
	const int blocks = slam.volume().stats().allocated_blocks;
	RgbdFrame zeros = rgbd_at(3 * FRAME_S);
	zeros.depth_m.setTo(0.0f);
	const DenseSlamFrame lost = slam.process(zeros);
	CHECK(lost.tracking.state == TrackingState::Lost);
	CHECK(lost.tracking.reason.find("valid depth") != std::string::npos);
	CHECK_FALSE(lost.integrated);
	CHECK(slam.integrated_count() == fused);
	CHECK(slam.volume().stats().allocated_blocks == blocks);
	CHECK(glm::length(slam.pose().translation - held.translation) == 0.0);
	// The camera is back where it was lost: re-tracked against the model.
	const DenseSlamFrame back = slam.process(rgbd_at(4 * FRAME_S));
	CHECK(back.tracking.state == TrackingState::Good);
	CHECK(glm::length(slam.pose().translation - living_room().trajectory.world_from_rgb(4 * FRAME_S).translation) < 0.01);
}

TEST_CASE("dense SLAM: a jump is never tracked as good and never fused") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 3; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	const size_t fused = slam.integrated_count();
	// A frame from 3 s further along the orbit (about 1.2 rad round the table).
	const DenseSlamFrame jump = slam.process(rgbd_at(3.0));
	CHECK(jump.tracking.state != TrackingState::Good);
	CHECK_FALSE(jump.integrated);
	CHECK(slam.integrated_count() == fused);
}

TEST_CASE("dense SLAM: a pose that moved faster than a hand is lost, the same move over its true time is tracked") {
	// The frame 0.3 s along the orbit, given its true time, then the same frame stamped a frame
	// after the last: the same images, the same ICP, only the speed differs.
	const Pose truth = living_room().trajectory.world_from_rgb(0.3);
	const double moved_m = glm::length(truth.translation - living_room().trajectory.world_from_rgb(2 * FRAME_S).translation);
	REQUIRE(moved_m > 3.0 * FRAME_S + 0.02); // faster than 3 m/s if it took one frame
	REQUIRE(moved_m < 3.0 * (0.3 - 2 * FRAME_S)); // a hand's speed over its true time
	for (const bool squeezed : { false, true }) {
		CAPTURE(squeezed);
		DenseSlam slam;
		start_slam(&slam, 0.0);
		for (int i = 0; i < 3; i++) {
			REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
		}
		const size_t fused = slam.integrated_count();
		RgbdFrame frame = rgbd_at(0.3);
		frame.timestamp_s = squeezed ? 3 * FRAME_S : 0.3;
		const DenseSlamFrame out = slam.process(frame);
		CAPTURE(out.tracking.reason);
		if (squeezed) {
			CHECK(out.tracking.state == TrackingState::Lost);
			CHECK(out.tracking.reason.find("faster than 3.0") != std::string::npos);
			CHECK_FALSE(out.integrated);
			CHECK(slam.integrated_count() == fused);
		} else {
			CHECK(out.tracking.state == TrackingState::Good);
			CHECK(glm::length(out.tracking.world_from_camera.translation - truth.translation) < 0.01);
		}
	}
}

TEST_CASE("dense SLAM: frames that do not fit the camera are refused with a reason") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	RgbdFrame bad = rgbd_at(0.0);
	cv::resize(bad.depth_m, bad.depth_m, cv::Size(100, 80));
	const DenseSlamFrame out = slam.process(bad);
	CHECK(out.tracking.state == TrackingState::Lost);
	CHECK(out.tracking.reason.find("320x240") != std::string::npos);
	DenseSlam unconfigured;
	CHECK(unconfigured.process(rgbd_at(0.0)).tracking.reason == "dense SLAM is not configured");
	CHECK(unconfigured.configure(PinholeParams(), Pose()) != "");
}

TEST_CASE("dense render: the cubemap faces are (mirrored) pinhole cameras with the cubemap's directions") {
	const int size = 16;
	for (int f = 0; f < 6; f++) {
		const Pose pose = cubemap_face_pose(f, glm::dvec3(0.0));
		PinholeParams face;
		face.width = face.height = size;
		face.fx = face.fy = 0.5 * size;
		face.cx = face.cy = 0.5 * (size - 1);
		for (const glm::dvec2 pixel : { glm::dvec2(0, 0), glm::dvec2(3, 11), glm::dvec2(15, 15) }) {
			// The camera is the face mirrored: its pixel (x, y) is the face's (N - 1 - x, y).
			const glm::dvec3 ray = glm::normalize(pose.rotation * unproject_pinhole(face, glm::dvec2(size - 1 - pixel.x, pixel.y)));
			const glm::dvec3 expected = cubemap_direction(f, pixel.x, pixel.y, size);
			CHECK(glm::length(ray - expected) < 1e-9);
		}
	}
}

TEST_CASE("dense render: the fused table top replaces the coarse floor below the probe, nothing else") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 10; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	// A probe 0.15 m above the middle of the table top (0.75 m), as the recordings' probe 0.
	const glm::dvec3 probe(2.5, 0.9, 2.0);
	Cubemap map = make_cubemap(32);
	for (cv::Mat &face : map.faces) {
		face.setTo(cv::Scalar(-1.0f, -1.0f, -1.0f)); // "coarse" marker
	}
	const DenseRenderStats stats = render_dense_over(slam.volume(), probe, DenseRenderOptions(), &map);
	CHECK(stats.texels_covered > 0);
	// Straight down (the -Y face's centre) is the table top, 0.15 m away: painted, in the table's
	// colour range (a beige noise texture: every channel well above black).
	const cv::Vec3f below = map.faces[3].at<cv::Vec3f>(16, 16);
	CHECK(below[0] > 0.2f);
	CHECK(below[1] > 0.2f);
	// Straight up is the ceiling, 1.6 m away, which the RGB-D camera looking at the table never
	// fused: the coarse model stays.
	const cv::Vec3f above = map.faces[2].at<cv::Vec3f>(16, 16);
	CHECK(above[0] == -1.0f);
}

TEST_CASE("dense SLAM: a jump of 0.5 m and 30 deg stays lost through relocalisation and is never fused") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 3; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	const size_t fused = slam.integrated_count();
	const Pose last = living_room().trajectory.world_from_rgb(2 * FRAME_S);
	// 0.5 m sideways and 30 deg about the vertical: still looking at the table, but further than the
	// tracker's jump limits and the relocalisation search's.
	Pose moved;
	moved.translation = glm::dvec3(0.5, 0.0, 0.0);
	moved.rotation = glm::angleAxis(glm::radians(30.0), glm::dvec3(0.0, 1.0, 0.0));
	const Pose jumped = compose(last, moved);
	for (int i = 3; i < 8; i++) {
		const double t = i * FRAME_S;
		const DenseSlamFrame out = slam.process(rgbd_frame(render_living_room(jumped, t, true, uint64_t(i) + 40), t));
		CAPTURE(out.tracking.reason);
		CHECK(out.tracking.state == TrackingState::Lost);
		CHECK_FALSE(out.integrated);
		CHECK_FALSE(out.tracking.relocalised);
	}
	CHECK(slam.integrated_count() == fused);
	CHECK(slam.relocalisation_attempts() == 5);
	CHECK(slam.relocalisation_count() == 0);
	CHECK(translation_difference_m(slam.pose(), last) < 0.01);
}

TEST_CASE("dense SLAM: after a blackout the camera is found 15 cm and 8 deg from where it was lost (relocalisation)") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 10; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	const Pose last = living_room().trajectory.world_from_rgb(9 * FRAME_S);
	// Covered lens for two frames while the camera moves on.
	for (int i = 10; i < 12; i++) {
		RgbdFrame dark = rgbd_at(i * FRAME_S);
		dark.depth_m.setTo(0.0f);
		REQUIRE(slam.process(dark).tracking.state == TrackingState::Lost);
	}
	Pose moved;
	moved.translation = glm::dvec3(0.12, 0.0, 0.09); // 15 cm
	moved.rotation = glm::angleAxis(glm::radians(8.0), glm::normalize(glm::dvec3(0.2, 1.0, 0.0)));
	const Pose found_at = compose(last, moved);
	// relocalised is set only when the plain re-track from the held pose failed and the search found it.
	const DenseSlamFrame out = slam.process(rgbd_frame(render_living_room(found_at, 12 * FRAME_S, true, 77), 12 * FRAME_S));
	CAPTURE(out.tracking.reason);
	REQUIRE(out.tracking.state == TrackingState::Good);
	CHECK(out.tracking.relocalised);
	CHECK(slam.relocalisation_count() == 1);
	CHECK(translation_difference_m(slam.pose(), found_at) < 0.01);
	CHECK(rotation_difference_deg(slam.pose(), found_at) < 0.5);
	MESSAGE("relocalised after a 15 cm / 8 deg move: error " << translation_difference_m(slam.pose(), found_at) * 1000.0 << " mm, "
												 << rotation_difference_deg(slam.pose(), found_at) << " deg; " << slam.relocalisation_attempts()
												 << " lost frames searched");
}

TEST_CASE("dense SLAM: a camera carried 2 m across the room while lost is relocalised at a keyframe within 10 frames, never Good before") {
	// 6.5 s round the table at 15 Hz keeps keyframes along the way; then the frames show the view
	// from where the camera was at 0.5 s, 2.1 m away, and go on from there (issue #41: the
	// search around the held pose cannot reach it; the keyframes can). Every frame reported Good
	// must lie within 2 cm of the truth.
	DenseSlam slam;
	start_slam(&slam, 0.0);
	const HandheldTrajectory &path = living_room().trajectory;
	int good = 0;
	const int sweep_frames = 98;
	for (int i = 0; i < sweep_frames; i++) {
		const double t = i * 2.0 * FRAME_S;
		const DenseSlamFrame out = slam.process(rgbd_at(t));
		if (out.tracking.state == TrackingState::Good) {
			good++;
			CHECK(translation_difference_m(slam.pose(), path.world_from_rgb(t)) < 0.02);
		}
	}
	CHECK(good >= sweep_frames - 2);
	const double sweep_end_s = (sweep_frames - 1) * 2.0 * FRAME_S;
	const double carried_m = translation_difference_m(path.world_from_rgb(sweep_end_s), path.world_from_rgb(0.5));
	REQUIRE(carried_m > 2.0);
	REQUIRE(slam.keyframe_count() >= 5);
	int found_at = -1;
	std::string reason;
	double searching_ms = 0.0; // the lost frames' tracking and searches, this build
	for (int k = 0; k < 20; k++) {
		const double scene_t = 0.5 + k * FRAME_S; // where the camera is now: the path from 0.5 s on
		const double clock_t = sweep_end_s + (k + 1) * FRAME_S; // the rig's clock goes on
		const Frame shot = render_living_room(path.world_from_rgb(scene_t), scene_t, true, uint64_t(k) + 500);
		const DenseSlamFrame out = slam.process(rgbd_frame(shot, clock_t));
		const double error_m = translation_difference_m(slam.pose(), path.world_from_rgb(scene_t));
		CAPTURE(k);
		CAPTURE(out.tracking.reason);
		if (found_at < 0) {
			searching_ms += out.timings.track_ms;
		}
		if (out.tracking.state != TrackingState::Good) {
			CHECK(found_at < 0); // once found, it holds
			continue;
		}
		CHECK(error_m < 0.02); // never Good while off
		if (found_at < 0) {
			found_at = k;
			reason = out.tracking.reason;
			CHECK(out.tracking.relocalised);
			CHECK(out.integrated);
		}
	}
	MESSAGE("carried ", carried_m, " m; ", slam.keyframe_count(), " keyframes; found at frame ", found_at, " after the move: ", reason, "; ",
			searching_ms, " ms of tracking and searching until then (320x240, this build)");
	REQUIRE(found_at >= 0);
	CHECK(found_at < 10);
	CHECK(reason.rfind("relocalised at keyframe ", 0) == 0);
	CHECK(slam.keyframe_relocalisation_count() == 1);
}

TEST_CASE("dense render: where the dense surface is the room's shell and the fisheye saw it, the coarse model stays") {
	DenseSlam slam;
	start_slam(&slam, 0.0);
	for (int i = 0; i < 10; i++) {
		REQUIRE(slam.process(rgbd_at(i * FRAME_S)).tracking.state == TrackingState::Good);
	}
	const RoomMeshResult mesh = build_room_mesh(living_room().scene.room.floorplan);
	REQUIRE_MESSAGE(mesh.ok, mesh.error);
	const CoarseCubemapRenderer renderer(mesh.mesh);
	const glm::dvec3 probe(2.5, 0.9, 2.0);
	const int size = 64;
	const cv::Vec3f marker(-1.0f, -1.0f, -1.0f); // "coarse"
	const cv::Mat atlas(mesh.mesh.atlas_height, mesh.mesh.atlas_width, CV_32FC3, cv::Scalar(marker[0], marker[1], marker[2]));
	const std::array<cv::Mat, 6> everywhere = renderer.render_channel(cv::Mat(atlas.size(), CV_32FC1, cv::Scalar::all(1.0)), probe, size);
	const std::array<cv::Mat, 6> nowhere = renderer.render_channel(cv::Mat(atlas.size(), CV_32FC1, cv::Scalar::all(0.0)), probe, size);
	// Painted texels, and those painted with a surface on the prism (the tolerance's distance).
	auto render = [&](const std::array<cv::Mat, 6> *p_observed, int *r_painted, int *r_on_shell) {
		Cubemap map = renderer.render(atlas, probe, size);
		const Cubemap prism = clone_cubemap(map);
		DenseRenderOptions options;
		options.coarse_observed = p_observed;
		render_dense_over(slam.volume(), probe, options, &map);
		*r_painted = *r_on_shell = 0;
		for (int f = 0; f < 6; f++) {
			for (int v = 0; v < size; v++) {
				for (int u = 0; u < size; u++) {
					if (map.faces[size_t(f)].at<cv::Vec3f>(v, u) == marker) {
						continue;
					}
					(*r_painted)++;
					const float dense = map.distance_m[size_t(f)].at<float>(v, u), shell = prism.distance_m[size_t(f)].at<float>(v, u);
					*r_on_shell += on_coarse_shell(dense, shell, options) ? 1 : 0;
				}
			}
		}
	};
	int painted_all = 0, shell_all = 0, painted_none = 0, shell_none = 0, painted_first = 0, shell_first = 0;
	render(nullptr, &painted_all, &shell_all);
	render(&nowhere, &painted_none, &shell_none);
	render(&everywhere, &painted_first, &shell_first);
	// The paper's rule paints the floor the camera fused too; with nothing observed by the fisheye
	// the same; with everything observed only what stands in the room (the table and its objects).
	CHECK(shell_all > 50);
	CHECK(painted_none == painted_all);
	CHECK(shell_first == 0);
	CHECK(painted_first == painted_all - shell_all);
	CHECK(painted_first > 100);
}
