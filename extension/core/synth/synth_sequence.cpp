// The synthetic recording (synth_sequence.h): the hand-held trajectories, the frame times of the
// two clocks, and write_sequence, which renders both streams and the ground truth into a
// recording. The checkerboard views it adds are in synth_calibration_views.cpp (split by concern
// to keep each file short).
#include <io/opencv.h>

#include "synth_sequence.h"

#include <recording/recording_writer.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <mutex>
#include <numbers>
#include <thread>

namespace roomprobe::synth {

namespace {

constexpr double PI = std::numbers::pi;

double seconds_since(std::chrono::steady_clock::time_point p_start) {
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - p_start).count();
}

double uniform_from(uint64_t p_seed, uint64_t p_index) {
	return static_cast<double>(mix_seed(p_seed, p_index) >> 11) * (1.0 / 9007199254740992.0);
}

// world_from_camera for a camera at p_position looking along p_forward with world +Y up,
// turned by p_roll about the optical axis (OpenCV frame: x right, y down, z forward).
glm::dquat look_rotation(const glm::dvec3 &p_forward, double p_roll) {
	const glm::dvec3 z = glm::normalize(p_forward);
	glm::dvec3 x = glm::cross(z, glm::dvec3(0.0, 1.0, 0.0));
	if (glm::length(x) < 1e-9) {
		x = glm::dvec3(1.0, 0.0, 0.0);
	}
	x = glm::normalize(x);
	glm::dvec3 y = glm::cross(z, x);
	const double c = std::cos(p_roll), s = std::sin(p_roll);
	const glm::dvec3 xr = c * x + s * y, yr = -s * x + c * y;
	return glm::normalize(glm::quat_cast(glm::dmat3(xr, yr, z)));
}

// Writes through RecordingWriter on a thread of its own, in the order given, so that encoding
// overlaps rendering. A bounded queue: push() waits while it is full.
class WriterThread {
public:
	using Job = std::function<RecordingStatus()>;

	explicit WriterThread(size_t p_capacity) :
			capacity(p_capacity), thread([this] { run(); }) {}
	~WriterThread() { finish(); }

	// False once a job has failed (error() says why): stop rendering.
	bool push(Job p_job, double *r_wait_s) {
		const auto start = std::chrono::steady_clock::now();
		std::unique_lock lock(mutex);
		space.wait(lock, [&] { return jobs.size() < capacity || !first_error.empty(); });
		*r_wait_s += seconds_since(start);
		if (!first_error.empty()) {
			return false;
		}
		jobs.push_back(std::move(p_job));
		ready.notify_one();
		return true;
	}
	// Waits for every job; returns the first error or "".
	std::string finish() {
		{
			std::lock_guard lock(mutex);
			stopping = true;
			ready.notify_one();
		}
		if (thread.joinable()) {
			thread.join();
		}
		return first_error;
	}
	std::string error() {
		std::lock_guard lock(mutex);
		return first_error;
	}

private:
	void run() {
		for (;;) {
			Job job;
			{
				std::unique_lock lock(mutex);
				ready.wait(lock, [&] { return !jobs.empty() || stopping; });
				if (jobs.empty()) {
					return;
				}
				job = std::move(jobs.front());
				jobs.pop_front();
				space.notify_one();
			}
			if (!error().empty()) {
				continue;
			}
			const RecordingStatus status = job();
			if (!status.ok) {
				std::lock_guard lock(mutex);
				if (first_error.empty()) {
					first_error = status.error.empty() ? "writing failed" : status.error;
				}
				space.notify_all();
			}
		}
	}

	size_t capacity;
	std::mutex mutex;
	std::condition_variable ready, space;
	std::deque<Job> jobs;
	bool stopping = false;
	std::string first_error;
	std::thread thread;
};

std::array<cv::Mat, 6> to_srgb8_faces(const std::array<cv::Mat, 6> &p_faces, double p_exposure) {
	std::array<cv::Mat, 6> out;
	for (int f = 0; f < 6; ++f) {
		out[f] = to_srgb8(p_faces[f], p_exposure);
	}
	return out;
}

// Both streams in time order on the RGB-D clock (RGB-D first at equal times).
struct Event {
	double time_s; // RGB-D clock
	bool fisheye;
	size_t index;
};

std::vector<Event> sequence_events(const std::vector<double> &p_rgbd_times, const std::vector<double> &p_fisheye_times, double p_fisheye_time_offset_s) {
	std::vector<Event> events;
	for (size_t i = 0; i < p_rgbd_times.size(); ++i) {
		events.push_back({ p_rgbd_times[i], false, i });
	}
	for (size_t k = 0; k < p_fisheye_times.size(); ++k) {
		events.push_back({ p_fisheye_times[k] + p_fisheye_time_offset_s, true, k });
	}
	std::stable_sort(events.begin(), events.end(), [](const Event &a, const Event &b) { return a.time_s < b.time_s; });
	return events;
}

// Renders write_sequence's events into their frames and queues the frames' writing on the writer
// thread: rgbd() and fisheye() return false once a write has failed (thread.error() says why).
struct EventRenderer {
	const SynthRenderer &renderer;
	const Rig &rig;
	const Scene &scene;
	const SequenceOptions &sequence;
	const std::vector<double> &rgbd_times;
	const std::vector<double> &fisheye_times;
	RecordingWriter &writer;
	WriterThread &thread;
	SequenceTimings &timings;
	double auto_multiplier = 1.0; // ExposureMode::Auto's state: the next frame's exposure over the reference

	bool rgbd(const Event &p_event, const Pose &p_world_from_rgb) {
		const auto t0 = std::chrono::steady_clock::now();
		RgbdOptions options = sequence.rgbd;
		options.noise_seed = mix_seed(sequence.seed, 0x10000000ULL + p_event.index);
		RgbdImage image = render_rgbd(renderer, rig.rgb, rig.depth_scale_m, p_world_from_rgb, p_event.time_s, options);
		timings.rgbd_s += seconds_since(t0);
		auto frame = std::make_shared<RgbdFrame>();
		frame->timestamp_s = rgbd_times[p_event.index];
		frame->rgb = image.rgb;
		frame->depth_m = image.depth;
		const double t = rgbd_times[p_event.index];
		const bool pushed = thread.push([&writer = writer, frame, t, world_from_rgb = p_world_from_rgb]() {
			RecordingStatus s = writer.add_rgbd(*frame);
			if (s.ok) {
				s = writer.add_ground_truth_pose(RecordingStream::Rgbd, t, world_from_rgb);
			}
			return s;
		}, &timings.write_wait_s);
		++timings.rgbd_frames;
		return pushed;
	}

	bool fisheye(const Event &p_event, const Pose &p_world_from_rgb) {
		if (!rig.has_fisheye()) {
			return truth_only(p_event);
		}
		const double t_fisheye = fisheye_times[p_event.index];
		const Pose world_from_fisheye = compose(p_world_from_rgb, rig.rgb_from_fisheye);
		auto t0 = std::chrono::steady_clock::now();
		FisheyeOptions fisheye_options = sequence.fisheye;
		double multiplier = 1.0;
		if (sequence.exposure_mode == ExposureMode::Bracket && !sequence.bracket_ev.empty()) {
			multiplier = std::pow(2.0, sequence.bracket_ev[p_event.index % sequence.bracket_ev.size()]);
		} else if (sequence.exposure_mode == ExposureMode::Auto) {
			multiplier = auto_multiplier;
		}
		fisheye_options.exposure *= multiplier;
		FisheyeImage image = render_fisheye(renderer, rig.fisheye, world_from_fisheye, p_event.time_s, fisheye_options);
		if (sequence.exposure_mode == ExposureMode::Auto) {
			// The mean code in the image circle (black outside it); codes go roughly as the
			// square root of the exposure, and the loop moves half way each frame.
			cv::Mat gray;
			cv::cvtColor(image.image, gray, cv::COLOR_RGB2GRAY);
			const double mean_code = cv::mean(gray, gray > 0)[0];
			if (mean_code > 0.0) {
				auto_multiplier = std::clamp(auto_multiplier * std::pow(sequence.auto_target_code / mean_code, 1.1), 1.0 / 64.0, 8.0);
			}
		}
		timings.fisheye_s += seconds_since(t0);
		const auto [faces, ldr] = truth_faces(p_event.time_s);
		auto frame = std::make_shared<FisheyeFrame>();
		frame->timestamp_s = t_fisheye;
		frame->hdr = sequence.fisheye_hdr;
		frame->image = sequence.fisheye_hdr ? image.radiance : image.image;
		frame->capture.exposure_us = SYNTH_EXPOSURE_UNIT_US * fisheye_options.exposure;
		frame->capture.gain = 0.0;
		const double t_rgbd = p_event.time_s;
		const bool pushed = thread.push([&writer = writer, frame, faces, ldr, t_fisheye, t_rgbd, world_from_fisheye]() {
			RecordingStatus s = writer.add_fisheye(*frame);
			if (s.ok) {
				s = writer.add_ground_truth_pose(RecordingStream::Fisheye, t_fisheye, world_from_fisheye);
			}
			if (s.ok) {
				s = writer.add_ground_truth_cubemap(t_rgbd, 0, *faces, *ldr);
			}
			return s;
		}, &timings.write_wait_s);
		++timings.fisheye_frames;
		++timings.cubemaps;
		return pushed;
	}

	// The true cubemap at the probe at p_time_s (RGB-D clock): linear, and as 8-bit sRGB.
	std::pair<std::shared_ptr<CubemapFaces>, std::shared_ptr<CubemapFaces>> truth_faces(double p_time_s) {
		const auto t0 = std::chrono::steady_clock::now();
		auto faces = std::make_shared<CubemapFaces>(render_cubemap(renderer, scene.probe_position, p_time_s, sequence.cubemap_face_size));
		auto ldr = std::make_shared<CubemapFaces>(to_srgb8_faces(*faces, sequence.cubemap_ldr_exposure));
		timings.cubemap_s += seconds_since(t0);
		return { faces, ldr };
	}

	// A rig without a fisheye (an RGB-D camera alone): the ground truth at the fisheye clock's
	// times all the same, so that a recording with and one without the fisheye are scored alike.
	bool truth_only(const Event &p_event) {
		const auto [faces, ldr] = truth_faces(p_event.time_s);
		const double t_rgbd = p_event.time_s;
		++timings.cubemaps;
		return thread.push([&writer = writer, faces, ldr, t_rgbd]() { return writer.add_ground_truth_cubemap(t_rgbd, 0, *faces, *ldr); }, &timings.write_wait_s);
	}
};

// synth.yaml beside the recording: what made it, for evaluations that need to know (e.g. when the
// light switches). "" or why it could not be written.
std::string write_synth_info(const std::string &p_folder, const Scene &p_scene, const SequenceOptions &p_options) {
	const std::string info_path = (std::filesystem::path(p_folder) / "synth.yaml").string();
	try {
		cv::FileStorage info(info_path, cv::FileStorage::WRITE);
		if (!info.isOpened()) {
			return info_path + ": cannot write";
		}
		info << "roomprobe_synth" << 1;
		info << "scene" << p_scene.name;
		info << "scene_panorama" << (p_options.scene_panorama_path.empty() ? std::string("none") : p_options.scene_panorama_path);
		info << "trajectory" << trajectory_name(p_scene.trajectory);
		info << "seed" << std::to_string(p_options.seed);
		info << "duration_s" << p_options.duration_s;
		info << "rgbd_rate_hz" << p_options.rgbd_rate_hz;
		info << "fisheye_rate_hz" << p_options.fisheye_rate_hz;
		info << "light_switch_s" << (std::isfinite(p_scene.light_switch_s) ? p_scene.light_switch_s : -1.0);
		if (p_scene.ceiling_light_half_size_m > 0.0) {
			info << "switched_light_center_m" << "[:" << p_scene.ceiling_light_center.x << p_scene.ceiling_light_center.y << p_scene.ceiling_light_center.z << "]";
			info << "switched_light_half_size_m" << p_scene.ceiling_light_half_size_m;
		}
		info << "fisheye_vignetting_edge_gain" << p_options.fisheye.vignetting_edge_gain;
		info << "fisheye_exposure" << p_options.fisheye.exposure;
		// Frames record their exposure in capture.txt: this is the one fisheye_exposure stands for.
		info << "fisheye_reference_exposure_us" << SYNTH_EXPOSURE_UNIT_US * p_options.fisheye.exposure;
		info << "fisheye_exposure_mode" << exposure_mode_name(p_options.exposure_mode);
		if (p_options.exposure_mode == ExposureMode::Bracket) {
			info << "fisheye_bracket_ev" << "[:";
			for (double ev : p_options.bracket_ev) {
				info << ev;
			}
			info << "]";
		}
		info << "fisheye_tone_curve" << tone_curve_name(p_options.fisheye.tone_curve);
		const glm::dvec3 &gains = p_options.fisheye.channel_gains;
		info << "fisheye_channel_gains" << "[:" << gains.x << gains.y << gains.z << "]";
		info << "rgb_tone_curve" << "srgb";
		info << "rgb_exposure" << p_options.rgbd.exposure;
		info << "depth_noise" << (p_options.rgbd.depth_noise ? 1 : 0);
		info << "cubemap_ldr_exposure" << p_options.cubemap_ldr_exposure;
		if (p_scene.panorama_scale > 0.0) {
			// The surfaces' radiance over the panorama's values (panorama_room).
			info << "panorama_scale" << p_scene.panorama_scale;
		}
	} catch (const cv::Exception &e) {
		return info_path + ": cannot write (" + e.what() + ")";
	}
	return "";
}

} // namespace

// ---------------------------------------------------------------- trajectory

HandheldTrajectory make_handheld_trajectory(const Scene &p_scene, uint64_t p_seed) {
	HandheldTrajectory trajectory;
	trajectory.kind = p_scene.trajectory;
	trajectory.target = p_scene.look_target;
	trajectory.radius_m = p_scene.orbit_radius_m;
	trajectory.height_m = p_scene.camera_height_m;
	trajectory.wall = p_scene.wall_sweep;
	trajectory.room = p_scene.room_sweep;
	if (p_scene.trajectory == TrajectoryKind::WallSweep) {
		// Draws of their own (indices 4, 5), so the orbit's draws stay what they were.
		trajectory.sweep_period_s = 9.0 + 2.0 * uniform_from(p_seed, 4);
		trajectory.sweep_sign = uniform_from(p_seed, 5) < 0.5 ? 1.0 : -1.0;
	}
	trajectory.start_angle_rad = 2.0 * PI * uniform_from(p_seed, 1);
	const double speed = 0.3 + 0.15 * uniform_from(p_seed, 2);
	trajectory.angular_speed_rad_s = uniform_from(p_seed, 3) < 0.5 ? speed : -speed;
	if (p_scene.orbit_loop_s > 0.0) {
		trajectory.angular_speed_rad_s = std::copysign(2.0 * PI / p_scene.orbit_loop_s, trajectory.angular_speed_rad_s);
	}
	for (size_t i = 0; i < trajectory.phases.size(); ++i) {
		trajectory.phases[i] = 2.0 * PI * uniform_from(p_seed, 10 + i);
	}
	if (p_scene.trajectory == TrajectoryKind::RoomSweep && uniform_from(p_seed, 6) < 0.5) {
		trajectory.room.turn_rad_s = -trajectory.room.turn_rad_s;
	}
	return trajectory;
}

Pose HandheldTrajectory::world_from_rgb(double p_t_s) const {
	const double t = p_t_s;
	const auto &p = phases;
	auto wave = [&](double p_period_s, int p_phase) { return std::sin(2.0 * PI * t / p_period_s + p[p_phase]); };
	if (kind == TrajectoryKind::WallSweep) {
		const glm::dvec3 up(0.0, 1.0, 0.0);
		const glm::dvec3 normal = glm::normalize(glm::dvec3(wall.normal.x, 0.0, wall.normal.z));
		const glm::dvec3 along = glm::cross(up, normal);
		// At rest at one end at t = 0, the other at half the period; the hand's own wobble on top.
		const double s = -sweep_sign * wall.half_length_m * std::cos(2.0 * PI * t / sweep_period_s) + 0.04 * wave(2.7, 0);
		const double distance = wall.distance_m + 0.22 * wave(6.1, 1) + 0.02 * wave(1.1, 3);
		const double height = height_m + 0.08 * wave(4.1, 2) + 0.012 * wave(1.3, 3);
		const glm::dvec3 on_wall(wall.wall_point.x, 0.0, wall.wall_point.z);
		const glm::dvec3 position = on_wall + s * along + distance * normal + glm::dvec3(0.0, height, 0.0);
		const double yaw = 0.08 * wave(3.3, 4) + 0.006 * wave(0.37, 8);
		const double pitch = 0.05 * wave(2.9, 5) + 0.005 * wave(0.41, 9);
		const double roll = 0.05 * wave(2.3, 7) + 0.004 * wave(0.29, 8);
		const glm::dvec3 level = std::cos(yaw) * -normal + std::sin(yaw) * along;
		Pose pose;
		pose.rotation = look_rotation(std::cos(pitch) * level + std::sin(pitch) * up, roll);
		pose.translation = position;
		return pose;
	}
	if (kind == TrajectoryKind::RoomSweep) {
		return room_sweep_pose(t);
	}
	const double angle = start_angle_rad + angular_speed_rad_s * t + 0.08 * wave(3.7, 0);
	const double radius = radius_m + 0.08 * wave(5.3, 1);
	const double height = height_m + 0.1 * wave(4.1, 2) + 0.015 * wave(1.3, 3);
	const glm::dvec3 position(target.x + radius * std::cos(angle), height, target.z + radius * std::sin(angle));
	// Where the hand points: the target, wandering by a few degrees, plus a little tremor.
	const glm::dvec3 look = target + glm::dvec3(0.1 * wave(2.9, 4) + 0.01 * wave(0.37, 8), 0.06 * wave(3.3, 5) + 0.008 * wave(0.41, 9), 0.1 * wave(3.1, 6));
	const double roll = 0.05 * wave(2.3, 7) + 0.004 * wave(0.29, 8);
	Pose pose;
	pose.rotation = look_rotation(look - position, roll);
	pose.translation = position;
	return pose;
}

Pose HandheldTrajectory::room_sweep_pose(double p_t_s) const {
	const double t = p_t_s;
	const auto &p = phases;
	auto wave = [&](double p_period_s, int p_phase) { return std::sin(2.0 * PI * t / p_period_s + p[p_phase]); };
	// Where along the path: a cosine over its length, at rest at both ends, there and back.
	double length_m = 0.0;
	for (size_t i = 1; i < room.path_xz.size(); ++i) {
		length_m += glm::length(room.path_xz[i] - room.path_xz[i - 1]);
	}
	double along_m = 0.5 * length_m * (1.0 - std::cos(PI * t / room.walk_s));
	glm::dvec2 on_path = room.path_xz.empty() ? glm::dvec2(0.0) : room.path_xz.front();
	for (size_t i = 1; i < room.path_xz.size(); ++i) {
		const double leg_m = glm::length(room.path_xz[i] - room.path_xz[i - 1]);
		if (along_m <= leg_m || i + 1 == room.path_xz.size()) {
			on_path = room.path_xz[i - 1] + (leg_m > 0.0 ? std::min(along_m / leg_m, 1.0) : 0.0) * (room.path_xz[i] - room.path_xz[i - 1]);
			break;
		}
		along_m -= leg_m;
	}
	const glm::dvec3 position(on_path.x + 0.05 * wave(2.7, 0), height_m + 0.08 * wave(4.1, 2) + 0.012 * wave(1.3, 3), on_path.y + 0.05 * wave(3.1, 1));
	// Turning round all the time; the camera dips to the floor and rises to the walls every 3.4 s
	// (16 degrees down at t = 0: a hand-held start is roughly level).
	const double yaw = start_angle_rad + room.turn_rad_s * t + 0.06 * wave(3.3, 4) + 0.006 * wave(0.37, 8);
	double pitch = -0.28 - 0.2 * std::sin(2.0 * PI * t / 3.4) + 0.005 * wave(0.41, 9);
	if (room.look_up_every_s > 0.0) {
		// Up to the ceiling at the end of each period: a raised cosine of 1.6 s, 1.25 rad high.
		const double pulse_s = 1.6, into = std::fmod(t, room.look_up_every_s) - (room.look_up_every_s - pulse_s);
		if (into > 0.0) {
			pitch += 1.25 * 0.5 * (1.0 - std::cos(2.0 * PI * into / pulse_s));
		}
	}
	const double roll = 0.05 * wave(2.3, 7) + 0.004 * wave(0.29, 8);
	const glm::dvec3 up(0.0, 1.0, 0.0);
	const glm::dvec3 level(std::cos(yaw), 0.0, std::sin(yaw));
	Pose pose;
	pose.rotation = look_rotation(std::cos(pitch) * level + std::sin(pitch) * up, roll);
	pose.translation = position;
	return pose;
}

// ---------------------------------------------------------------- the recording

const char *exposure_mode_name(ExposureMode p_mode) {
	switch (p_mode) {
		case ExposureMode::Auto:
			return "auto";
		case ExposureMode::Bracket:
			return "bracket";
		default:
			return "fixed";
	}
}

std::vector<double> rgbd_frame_times(const SequenceOptions &p_options) {
	std::vector<double> times;
	if (!(p_options.rgbd_rate_hz > 0.0)) {
		return times;
	}
	for (int64_t i = 0;; ++i) {
		const double t = static_cast<double>(i) / p_options.rgbd_rate_hz;
		if (t >= p_options.duration_s) {
			break;
		}
		times.push_back(t);
	}
	return times;
}

std::vector<double> fisheye_frame_times(const SequenceOptions &p_options, double p_fisheye_time_offset_s) {
	std::vector<double> times;
	const std::vector<double> rgbd = rgbd_frame_times(p_options);
	if (rgbd.empty() || !(p_options.fisheye_rate_hz > 0.0)) {
		return times;
	}
	const double first = rgbd.front(), last = rgbd.back();
	const int64_t k0 = static_cast<int64_t>(std::ceil((first - p_fisheye_time_offset_s) * p_options.fisheye_rate_hz - 1e-9));
	for (int64_t k = std::max<int64_t>(k0, 0);; ++k) {
		const double t = static_cast<double>(k) / p_options.fisheye_rate_hz;
		const double on_rgbd_clock = t + p_fisheye_time_offset_s;
		if (on_rgbd_clock > last + 1e-12) {
			break;
		}
		if (on_rgbd_clock >= first) {
			times.push_back(t);
		}
	}
	return times;
}

SequenceResult write_sequence(const std::string &p_folder, const Rig &p_rig, const Scene &p_scene, const SequenceOptions &p_options) {
	SequenceResult result;
	SequenceTimings &timings = result.timings;
	const auto start = std::chrono::steady_clock::now();
	auto progress = [&](const std::string &p_line) {
		if (p_options.progress) {
			p_options.progress(p_line);
		}
	};
	if (!(p_options.duration_s > 0.0) || !(p_options.rgbd_rate_hz > 0.0) || !(p_options.fisheye_rate_hz > 0.0) || p_options.cubemap_face_size <= 0) {
		result.error = "the duration, both frame rates and the cubemap size must be positive";
		return result;
	}

	auto scene_start = std::chrono::steady_clock::now();
	const SynthRenderer renderer(p_scene);
	if (!renderer.ok()) {
		result.error = "scene '" + p_scene.name + "': " + renderer.error();
		return result;
	}
	timings.scene_s = seconds_since(scene_start);

	const HandheldTrajectory trajectory = make_handheld_trajectory(p_scene, p_options.seed);
	const std::vector<double> rgbd_times = rgbd_frame_times(p_options);
	const std::vector<double> fisheye_times = fisheye_frame_times(p_options, p_rig.fisheye_time_offset_s);

	RoomInfo room;
	room.floorplan = p_scene.room.floorplan;
	room.initial_rgb_pose = trajectory.world_from_rgb(rgbd_times.front());
	room.probes = { p_scene.probe_position };
	RecordingWriter writer;
	RecordingWriteOptions write_options;
	write_options.exr_full_float = p_options.exr_full_float;
	write_options.frame_format = p_options.frame_format;
	RecordingStatus status = writer.open(p_folder, p_rig, room, write_options);
	if (!status.ok) {
		result.error = status.error;
		return result;
	}
	progress("scene '" + p_scene.name + "': " + std::to_string(renderer.triangle_count()) + " triangles; " + std::to_string(rgbd_times.size()) +
			" RGB-D frames, " + std::to_string(fisheye_times.size()) + " fisheye frames");

	const std::vector<Event> events = sequence_events(rgbd_times, fisheye_times, p_rig.fisheye_time_offset_s);

	WriterThread thread(4);
	EventRenderer render{ renderer, p_rig, p_scene, p_options, rgbd_times, fisheye_times, writer, thread, timings };
	bool stopped = false;
	size_t done = 0;
	for (const Event &event : events) {
		const Pose world_from_rgb = trajectory.world_from_rgb(event.time_s);
		stopped = !(event.fisheye ? render.fisheye(event, world_from_rgb) : render.rgbd(event, world_from_rgb));
		if (stopped) {
			break;
		}
		++done;
		if (done % 60 == 0) {
			char line[128];
			std::snprintf(line, sizeof(line), "%zu/%zu frames, %.1f s", done, events.size(), seconds_since(start));
			progress(line);
		}
	}
	const auto wait_start = std::chrono::steady_clock::now();
	std::string error = thread.finish();
	timings.write_wait_s += seconds_since(wait_start);
	status = writer.close();
	if (error.empty() && !status.ok) {
		error = status.error;
	}
	if (!error.empty()) {
		result.error = error;
		return result;
	}

	// What made this recording, for evaluations that need to know (e.g. when the light switches).
	error = write_synth_info(p_folder, p_scene, p_options);
	if (!error.empty()) {
		result.error = error;
		return result;
	}

	if (p_options.calibration_views && p_rig.has_fisheye()) { // the views calibrate the rig's two cameras together
		const auto t0 = std::chrono::steady_clock::now();
		const CalibrationResult calibration =
				write_calibration_views(p_folder, p_rig, CheckerboardSpec(), p_options.calibration_samples_per_axis, p_options.fisheye, progress);
		if (!calibration.ok) {
			result.error = calibration.error;
			return result;
		}
		timings.calibration_views = calibration.views;
		if (p_options.photometric_views && p_rig.has_fisheye()) {
			const Pose world_from_fisheye = compose(trajectory.world_from_rgb(rgbd_times.front()), p_rig.rgb_from_fisheye);
			progress("calibration views: the exposure sweep and the flat field (photometric calibration)");
			const CalibrationResult photometric = write_photometric_views(p_folder, renderer, p_rig.fisheye, world_from_fisheye, p_options.fisheye);
			if (!photometric.ok) {
				result.error = photometric.error;
				return result;
			}
			timings.calibration_views += photometric.views;
		}
		timings.calibration_s = seconds_since(t0);
	}
	timings.total_s = seconds_since(start);
	result.ok = true;
	return result;
}

} // namespace roomprobe::synth
