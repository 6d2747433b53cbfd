#pragma once
// Synthetic RGB-D frames of the living room at known poses, for the dense SLAM tests
// (test_slam_tracking.cpp, test_slam_dense.cpp, test_gpu_tracking.cpp). Frames are rendered at 320x240 (the test rig's
// camera at half size) to keep the suite fast.

#include "synth_test_rig.h"

#include "math/pose.h"
#include "recording/recording_types.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <limits>
#include <memory>
#include <numbers>

namespace synth_frames {

using namespace roomprobe;
using namespace roomprobe::synth;

// The test rig's RGB-D camera at half size: same field of view, a quarter of the pixels.
inline PinholeParams half_camera() {
	PinholeParams camera = test_rig().rgb;
	camera.width /= 2;
	camera.height /= 2;
	camera.fx *= 0.5;
	camera.fy *= 0.5;
	camera.cx = (camera.cx + 0.5) * 0.5 - 0.5;
	camera.cy = (camera.cy + 0.5) * 0.5 - 0.5;
	return camera;
}

struct LivingRoom {
	Scene scene;
	std::unique_ptr<SynthRenderer> renderer;
	HandheldTrajectory trajectory;
};

// One renderer for every test case: building the Embree scene is the slow part.
inline const LivingRoom &living_room() {
	static const std::unique_ptr<LivingRoom> room = [] {
		auto r = std::make_unique<LivingRoom>();
		const SceneResult result = make_scene("living_room", SceneOptions());
		REQUIRE_MESSAGE(result.ok, result.error);
		r->scene = result.scene;
		r->renderer = std::make_unique<SynthRenderer>(r->scene);
		REQUIRE_MESSAGE(r->renderer->ok(), r->renderer->error());
		r->trajectory = make_handheld_trajectory(r->scene, 1);
		return r;
	}();
	return *room;
}

struct Frame {
	cv::Mat depth_m; // CV_32FC1, NaN = none
	cv::Mat rgb;
};

// The frame as DenseSlam takes it, stamped p_time_s on the RGB-D clock.
inline RgbdFrame rgbd_frame(const Frame &p_frame, double p_time_s) {
	RgbdFrame out;
	out.timestamp_s = p_time_s;
	out.rgb = p_frame.rgb;
	out.depth_m = p_frame.depth_m;
	return out;
}

// The frame the camera sees at a pose. Noise-free: the renderer's exact z where the sensor has a
// reading (its holes kept, no 1 mm quantisation). Noisy: the sensor's depth with Kinect-like axial
// noise (kinect_depth_sigma_m), in millimetres.
inline Frame render(const SynthRenderer &p_renderer, const PinholeParams &p_camera, const Pose &p_pose, double p_time_s, bool p_noisy, uint64_t p_seed) {
	RgbdOptions options;
	options.depth_noise = p_noisy;
	options.noise_seed = p_seed;
	const double scale = 0.001;
	const RgbdImage image = render_rgbd(p_renderer, p_camera, scale, p_pose, p_time_s, options);
	Frame frame;
	frame.rgb = image.rgb;
	frame.depth_m.create(image.depth.size(), CV_32FC1);
	for (int y = 0; y < image.depth.rows; ++y) {
		for (int x = 0; x < image.depth.cols; ++x) {
			const uint16_t raw = image.depth.at<uint16_t>(y, x);
			float value = std::numeric_limits<float>::quiet_NaN();
			if (raw != 0) {
				value = p_noisy ? float(raw * scale) : image.depth_true_m.at<float>(y, x);
			}
			frame.depth_m.at<float>(y, x) = value;
		}
	}
	return frame;
}

inline Frame render_living_room(const Pose &p_pose, double p_time_s, bool p_noisy, uint64_t p_seed = 7) {
	return render(*living_room().renderer, half_camera(), p_pose, p_time_s, p_noisy, p_seed);
}

// p_pose moved in its own camera frame: rotated by p_angle_deg about p_axis, then translated.
inline Pose moved(const Pose &p_pose, const glm::dvec3 &p_axis, double p_angle_deg, const glm::dvec3 &p_translation_m) {
	Pose delta;
	delta.rotation = glm::angleAxis(p_angle_deg * std::numbers::pi / 180.0, glm::normalize(p_axis));
	delta.translation = p_translation_m;
	return compose(p_pose, delta);
}

} // namespace synth_frames
