#pragma once
// The live engine's test recording (test_engine_live_room.cpp, test_gpu_tracking.cpp): the
// synthetic living room of synth_test_frames.h, 0.6 s of it: 18 RGB-D frames at 320x240 and the
// fisheye frames of a 256x256 fisheye in between, rendered once in memory and shared; and the
// engine configuration that plays it with every stage on.

#include "engine/live_room.h"
#include "rig/photometry.h"
#include "synth/synth_renderer.h"
#include "synth_test_frames.h"
#include "synth_test_rig.h"

#include <memory>
#include <vector>

namespace engine_test {

using namespace roomprobe;

inline constexpr double RGBD_RATE_HZ = 30.0;
inline constexpr double FISHEYE_RATE_HZ = 12.0;
inline constexpr int RGBD_FRAMES = 18; // 0.6 s

struct Event {
	bool fisheye = false;
	size_t index = 0;
};

struct Recording {
	Rig rig;
	RigPhotometry photometry;
	Floorplan floorplan;
	Pose initial_rgb_pose;
	glm::dvec3 probe = glm::dvec3(0.0);
	std::vector<RgbdFrame> rgbd;
	std::vector<FisheyeFrame> fisheye;
	std::vector<Event> events; // both streams in time order on the RGB-D clock, RGB-D first at equal times
};

// Rendered once: the RGB-D frames as test_slam_dense.cpp renders them (noisy depth, 320x240), and
// 8-bit fisheye frames with the synthetic rig's photometry (exposure 1, vignetting to 0.5 at the
// rim), each at its own clock's time, as synth/synth_sequence.cpp times them.
inline const Recording &recording() {
	static const std::unique_ptr<Recording> rec = [] {
		auto r = std::make_unique<Recording>();
		const synth_frames::LivingRoom &room = synth_frames::living_room();
		r->rig = test_rig();
		r->rig.rgb = synth_frames::half_camera();
		r->rig.fisheye = scaled_test_fisheye(4); // 256 x 256
		const synth::FisheyeOptions fisheye_options;
		const synth::RgbdOptions rgbd_options;
		r->photometry.known = true;
		r->photometry.fisheye = tone_curve_photometry(fisheye_options.tone_curve, fisheye_options.exposure, fisheye_options.channel_gains);
		r->photometry.fisheye.vignetting = radial_vignetting_table(fisheye_options.vignetting_edge_gain);
		r->photometry.rgb = tone_curve_photometry(ToneCurve::Srgb, rgbd_options.exposure);
		r->floorplan = room.scene.room.floorplan;
		r->initial_rgb_pose = room.trajectory.world_from_rgb(0.0);
		r->probe = room.scene.probe_position;
		for (int i = 0; i < RGBD_FRAMES; i++) {
			const double t = i / RGBD_RATE_HZ;
			const synth_frames::Frame frame = synth_frames::render_living_room(room.trajectory.world_from_rgb(t), t, true, uint64_t(i) + 11);
			RgbdFrame out;
			out.timestamp_s = t;
			out.rgb = frame.rgb;
			out.depth_m = frame.depth_m;
			r->rgbd.push_back(out);
		}
		const double last_rgbd = (RGBD_FRAMES - 1) / RGBD_RATE_HZ;
		for (int k = 0;; k++) {
			const double t = k / FISHEYE_RATE_HZ; // fisheye clock
			const double on_rgbd_clock = t + r->rig.fisheye_time_offset_s;
			if (on_rgbd_clock > last_rgbd) {
				break;
			}
			const Pose world_from_fisheye = compose(room.trajectory.world_from_rgb(on_rgbd_clock), r->rig.rgb_from_fisheye);
			FisheyeFrame out;
			out.timestamp_s = t;
			out.image = synth::render_fisheye(*room.renderer, r->rig.fisheye, world_from_fisheye, on_rgbd_clock, fisheye_options).image;
			out.hdr = false;
			r->fisheye.push_back(out);
		}
		size_t i = 0, k = 0;
		while (i < r->rgbd.size() || k < r->fisheye.size()) {
			const bool take_fisheye = i >= r->rgbd.size() ||
					(k < r->fisheye.size() && r->fisheye[k].timestamp_s + r->rig.fisheye_time_offset_s < r->rgbd[i].timestamp_s);
			r->events.push_back(take_fisheye ? Event{ true, k++ } : Event{ false, i++ });
		}
		return r;
	}();
	return *rec;
}

inline LiveRoomConfig live_config(const Recording &p_rec) {
	LiveRoomConfig cfg;
	cfg.has_rig = true;
	cfg.rig = p_rec.rig;
	cfg.photometry = p_rec.photometry;
	cfg.has_room = true;
	cfg.floorplan = p_rec.floorplan;
	cfg.initial_rgb_pose = p_rec.initial_rgb_pose;
	cfg.keep_points = { p_rec.probe };
	cfg.dense = true;
	cfg.coarse_poses = PoseSource::Tracked;
	cfg.dense_poses = PoseSource::Tracked;
	cfg.coarse.texel_size_m = 0.05; // a small atlas keeps the debug build fast
	cfg.coarse.rgb_texture = true; // the RGB camera's texturing, off by default, runs through the engine too
	cfg.coarse.inpaint = true;
	cfg.coarse.inpaint_async = false;
	cfg.coarse.lighting = true;
	return cfg;
}

inline void push_event(LiveRoom &p_engine, const Recording &p_rec, const Event &p_event) {
	if (p_event.fisheye) {
		p_engine.push_fisheye(p_rec.fisheye[p_event.index]);
	} else {
		p_engine.push_rgbd(p_rec.rgbd[p_event.index]);
	}
}

} // namespace engine_test
