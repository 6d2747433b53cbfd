#pragma once
// What live_room*.cpp share and nothing else includes: the engine's clock, the workers' poll
// interval, and LiveRoom's private Probe and Frames. (The class is one object in three files:
// live_room.cpp configures and runs the workers, live_room_frames.cpp takes frames in and keeps
// the room, live_room_probes.cpp renders the probes and hands out results.)

#include "live_room.h"

#include <chrono>

namespace roomprobe::live_room_detail {

using Clock = std::chrono::steady_clock;

inline double now_s() {
	return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

inline double ms_since(double p_start_s) {
	return (now_s() - p_start_s) * 1000.0;
}

// How long a worker waits on an empty mailbox before it looks at the stop flag again.
constexpr std::chrono::milliseconds WORKER_POLL(50);
// Arrival times kept for the latency figures (frames older than this many are forgotten).
constexpr size_t ARRIVALS_KEPT = 256;

// CoarseSnapshot::observed of a texture: where the fisheye observed each texel, or, without a
// fisheye (p_rgb_only), where the RGB camera did: the texels the coarse model saw itself.
inline cv::Mat observed_mask(const CoarseTexture &p_texture, bool p_rgb_only) {
	cv::Mat observed;
	const cv::Mat seen = p_rgb_only ? p_texture.observed : cv::Mat(p_texture.quality > 0.0f);
	if (seen.empty()) {
		return observed;
	}
	seen.convertTo(observed, CV_32F, 1.0 / 255.0); // 255 or 0 -> 1 or 0
	return observed;
}

} // namespace roomprobe::live_room_detail

namespace roomprobe {

struct LiveRoom::Probe {
	glm::dvec3 position = glm::dvec3(0.0);
	int size = 128;
	bool dirty = true; // moved, resized or new since its last map
	uint64_t version = 0;
	uint64_t rendered_generation = 0; // the input_generation its newest map was rendered from
	std::shared_ptr<const ProbeMap> map;
	DenseFaceCache dense_faces; // its dense faces between maps
	std::shared_ptr<const VirtualScene> objects; // drawn over the room (may be null)
};

struct LiveRoom::Frames {
	struct Rgbd {
		RgbdFrame frame;
		uint64_t sequence = 0;
	};
	struct Fisheye {
		FisheyeFrame frame;
		uint64_t sequence = 0;
	};
	Mailbox<Rgbd> rgbd;
	Mailbox<Fisheye> fisheye;
	// Frames a worker has finished. Every frame put is either dropped or finished, so
	// put - dropped - done is the work still to do, with no gap between a take and its start.
	std::atomic<uint64_t> rgbd_done{ 0 }, fisheye_done{ 0 };

	bool rgbd_outstanding() const { return rgbd.put_count() - rgbd.dropped_count() > rgbd_done; }
	bool fisheye_outstanding() const { return fisheye.put_count() - fisheye.dropped_count() > fisheye_done; }
};

} // namespace roomprobe
