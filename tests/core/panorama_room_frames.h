#pragma once
// RGB-D frames of the synthetic panorama_room with their ground truth, for dense tracking tests.
//
// The scene (synth/synth_scene.h, make_scene("panorama_room")): a bare 5 (x) x 4 (z) x 2.6 m box,
// floor at y = 0, no furniture, whose walls, floor and ceiling show the real panorama
// ../shared/data/hdri/lebombo_1k.hdr as seen from the room's centre (2.5, 1.3, 2), unlit, times
// scene.panorama_scale (about 0.37: 8-bit images at exposure 1 are neither black nor saturated,
// apart from the photograph's own window). Flat walls whose only texture is the photograph:
// geometry alone cannot fix a translation along a wall, a photometric term can.
//
// The trajectory (synth/synth_sequence.h, TrajectoryKind::WallSweep): the RGB-D camera faces
// wall 0 (the plane z = 0, normal +z into the room) from 1.26 to 1.74 m, 1.3 to 1.5 m high,
// sweeping sideways along it (x from about 1.56 to 3.44 m and back in 9 to 11 s, at rest at the
// ends; up to 0.75 m/s, 0.42 m/s on average) with hand-held yaw, pitch and roll wander of a few
// degrees (the optical axis within 6 degrees of -z; up to 20 degrees/s). Every depth pixel of
// every frame lies on that one plane.
//
// Usage (doctest):
//
//   #include "panorama_room_frames.h"
//   std::string reason;
//   if (!panorama_room_frames::available(&reason)) {
//       MESSAGE("skipped: " << reason);
//       return;
//   }
//   panorama_room_frames::FrameOptions options; // 320x240, frames 0..29, noisy depth, seed 1
//   options.count = 10;
//   const std::vector<panorama_room_frames::Frame> frames = panorama_room_frames::render_frames(options);
//   const roomprobe::PinholeIntrinsics camera = roomprobe::pinhole_intrinsics(panorama_room_frames::camera(320, 240));
//   // frames[i].depth_m, frames[i].rgb, frames[i].world_from_camera, frames[i].timestamp_s
//
// API (namespace panorama_room_frames):
//   available(r_reason)   false (and why) when the panorama is missing; call it first and skip.
//   room()                the scene, its renderer and the trajectory of a seed, built once per
//                         process and seed (REQUIREs available()).
//   camera(w, h)          the synthetic rig's RGB-D camera (640x480, fx = fy = 525, no distortion)
//                         scaled to w x h, which must be 4:3 and at most 640 wide (640x480,
//                         320x240, 160x120...). Same field of view.
//   pose_at(t, seed)      the true world_from_camera (OpenCV axes: x right, y down, z forward;
//                         world Y up, metres) at any t on the RGB-D clock: exact, closed form.
//   render_frame(i, o)    frame i (at t = i / RATE_HZ), rendered with o's size, noise and seed.
//   render_frames(o)      frames o.first, o.first + o.stride, ... (o.count of them).
//
// A frame at 640x480 with noisy depth and seed s is the very frame i of
// `./roomprobe synth --scene panorama_room --seed s` (same RGB bytes, same depth in mm):
// the same trajectory, noise seed and depth model (Kinect-like axial noise, 1 mm steps, no
// reading beyond 75 degrees incidence or outside [0.4, 8] m; the room is convex and empty, so
// there are no edges or projector shadows, and the projector's shadow rays are skipped here).
//
// Cost (debug build, 2 cores): about 3 ms a frame at 160x120, 10 ms at 320x240 and 42 ms at
// 640x480; the first call also reads the panorama and builds the scene (about 35 ms).

#include "synth_test_rig.h"

#include "camera/pinhole_camera.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace panorama_room_frames {

constexpr double RATE_HZ = 30.0; // the RGB-D frame rate: frame i is at i / RATE_HZ seconds

inline std::string panorama_path() {
	return std::string(ROOMPROBE_SHARED_DATA) + "/hdri/lebombo_1k.hdr";
}

inline bool available(std::string *r_reason) {
	std::error_code ec;
	if (std::filesystem::is_regular_file(panorama_path(), ec)) {
		return true;
	}
	if (r_reason) {
		*r_reason = panorama_path() + " is missing (../shared/data/hdri), so panorama_room cannot be built";
	}
	return false;
}

struct Room {
	roomprobe::synth::Scene scene;
	std::unique_ptr<roomprobe::synth::SynthRenderer> renderer;
	roomprobe::synth::HandheldTrajectory trajectory;
	glm::dvec3 wall_normal = glm::dvec3(0.0); // of the swept wall, into the room (+z)
	glm::dvec3 along_wall = glm::dvec3(0.0); // horizontal, along the swept wall (the sliding direction)
};

// Built once per seed: reading the panorama is the slow part.
inline const Room &room(uint64_t p_seed = 1) {
	static std::mutex mutex;
	static std::map<uint64_t, std::unique_ptr<Room>> rooms;
	std::lock_guard lock(mutex);
	std::unique_ptr<Room> &entry = rooms[p_seed];
	if (!entry) {
		std::string reason;
		REQUIRE_MESSAGE(available(&reason), reason);
		auto r = std::make_unique<Room>();
		roomprobe::synth::SceneOptions options;
		options.panorama_path = panorama_path();
		roomprobe::synth::SceneResult result = roomprobe::synth::make_scene("panorama_room", options);
		REQUIRE_MESSAGE(result.ok, result.error);
		r->scene = std::move(result.scene);
		r->renderer = std::make_unique<roomprobe::synth::SynthRenderer>(r->scene);
		REQUIRE_MESSAGE(r->renderer->ok(), r->renderer->error());
		r->trajectory = roomprobe::synth::make_handheld_trajectory(r->scene, p_seed);
		r->wall_normal = r->scene.wall_sweep.normal;
		r->along_wall = glm::cross(glm::dvec3(0.0, 1.0, 0.0), r->wall_normal);
		entry = std::move(r);
	}
	return *entry;
}

inline roomprobe::PinholeParams camera(int p_width, int p_height) {
	roomprobe::PinholeParams camera = test_rig().rgb;
	REQUIRE_MESSAGE((p_width > 0 && p_width <= camera.width && p_width * camera.height == p_height * camera.width),
			"panorama_room_frames::camera: " << p_width << "x" << p_height << " is not 4:3 at most 640x480");
	// Pixel centres at integers: the image's edges, not its first pixel centres, scale.
	const double s = double(p_width) / camera.width;
	camera.width = p_width;
	camera.height = p_height;
	camera.fx *= s;
	camera.fy *= s;
	camera.cx = (camera.cx + 0.5) * s - 0.5;
	camera.cy = (camera.cy + 0.5) * s - 0.5;
	return camera;
}

inline roomprobe::Pose pose_at(double p_time_s, uint64_t p_seed = 1) {
	return room(p_seed).trajectory.world_from_rgb(p_time_s);
}

struct FrameOptions {
	int width = 320, height = 240; // 4:3, at most 640x480
	int first = 0; // the first frame's index
	int count = 30; // how many
	int stride = 1; // every stride-th frame
	// true: the sensor's depth (Kinect-like axial noise, 1 mm steps), as the recording has it;
	// false: the exact z wherever the sensor has a reading.
	bool noisy = true;
	uint64_t seed = 1; // the trajectory's and the noise's, as --seed
};

struct Frame {
	int index = 0;
	double timestamp_s = 0.0; // index / RATE_HZ, RGB-D clock
	roomprobe::Pose world_from_camera; // ground truth, exact
	cv::Mat rgb; // CV_8UC3, R, G, B (sRGB, exposure 1)
	cv::Mat depth_m; // CV_32FC1, z metres in the camera frame, NaN = no reading
	cv::Mat depth_true_m; // CV_32FC1, the noise-free z of every pixel (0 where nothing is hit)
};

inline Frame render_frame(int p_index, const FrameOptions &p_options) {
	using namespace roomprobe::synth;
	const Room &r = room(p_options.seed);
	const roomprobe::PinholeParams cam = camera(p_options.width, p_options.height);
	Frame frame;
	frame.index = p_index;
	frame.timestamp_s = p_index / RATE_HZ;
	frame.world_from_camera = r.trajectory.world_from_rgb(frame.timestamp_s);
	RgbdOptions options;
	options.depth_noise = p_options.noisy;
	// As write_sequence seeds frame i.
	options.noise_seed = mix_seed(p_options.seed, 0x10000000ULL + static_cast<uint64_t>(p_index));
	// A convex, empty room has no projector shadows: the same images without the shadow rays.
	options.projector_baseline_m = 0.0;
	const double scale = test_rig().depth_scale_m;
	const RgbdImage image = render_rgbd(*r.renderer, cam, scale, frame.world_from_camera, frame.timestamp_s, options);
	frame.rgb = image.rgb;
	frame.depth_true_m = image.depth_true_m;
	frame.depth_m.create(image.depth.size(), CV_32FC1);
	for (int y = 0; y < image.depth.rows; ++y) {
		const uint16_t *raw = image.depth.ptr<uint16_t>(y);
		const float *exact = image.depth_true_m.ptr<float>(y);
		float *out = frame.depth_m.ptr<float>(y);
		for (int x = 0; x < image.depth.cols; ++x) {
			out[x] = raw[x] == 0 ? std::numeric_limits<float>::quiet_NaN() : (p_options.noisy ? float(raw[x] * scale) : exact[x]);
		}
	}
	return frame;
}

inline std::vector<Frame> render_frames(const FrameOptions &p_options) {
	std::vector<Frame> frames;
	frames.reserve(std::max(0, p_options.count));
	for (int k = 0; k < p_options.count; ++k) {
		frames.push_back(render_frame(p_options.first + k * std::max(1, p_options.stride), p_options));
	}
	return frames;
}

} // namespace panorama_room_frames
