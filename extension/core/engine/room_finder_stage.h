#pragma once
// The room finder stage of the live engine (issue #18, LiveRoomConfig::find_room): it keeps fisheye
// frames spread over the sweep, estimates the room from the dense model's surface, the camera path
// and those frames (room/room_from_sweep.h), and publishes each estimate as an immutable FoundRoom.
// One lock guards its views and its newest estimate; the estimate itself runs outside it.

#include <recording/recording_types.h>
#include <room/room_from_sweep.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

namespace roomprobe {

// The room found from the sweep so far, in the engine's world (the model frame of
// room/room_from_sweep.h): result.estimate.world_from_model maps the engine's world into the
// room found, so the room's pose in the world is its inverse.
struct FoundRoom {
	uint64_t version = 0; // 1, 2, ... per estimate
	RoomFromSweep result;
	std::vector<SurfaceSample> samples; // the dense surface it was found on, engine world
	size_t fused_frames = 0; // the dense model's fused frames then
	size_t fisheye_views = 0; // fisheye frames searched
	double seconds = 0.0; // how long the estimate took
};

class RoomFinderStage {
public:
	// Forgets the views and the estimates (a new configuration).
	void reset();
	// Keeps p_frame when it is at least the current spacing after the last view kept. At
	// 2 x p_max_views views every other one goes and the spacing doubles, so the views stay spread
	// over the whole sweep. p_max_views 0: keeps none.
	void keep_view(const FisheyeFrame &p_frame, size_t p_max_views);
	std::vector<FisheyeFrame> views() const;

	// Estimates from p_observed (the caller fills everything but the fisheye views' poses' source)
	// and publishes the estimate with the dense mesh version it saw. p_has_dense false: an estimate
	// that says dense SLAM is needed.
	// p_start: when gathering p_observed began (FoundRoom::seconds counts from it).
	std::shared_ptr<const FoundRoom> estimate(SweepObservations p_observed, bool p_has_dense, size_t p_fused_frames, uint64_t p_mesh_version,
			const RoomEstimationOptions &p_options, std::chrono::steady_clock::time_point p_start);
	// Publishes an estimate that failed with p_message.
	std::shared_ptr<const FoundRoom> publish_failure(const std::string &p_message);
	std::shared_ptr<const FoundRoom> found() const;
	uint64_t estimated_mesh_version() const; // the dense mesh version of the newest estimate

	// The stage's worker: waits p_interval_s (or until wake()); false when p_stopping was set.
	bool wait(double p_interval_s, const std::atomic<bool> &p_stopping);
	void wake();

private:
	std::shared_ptr<const FoundRoom> publish(std::shared_ptr<FoundRoom> p_found, uint64_t p_mesh_version);

	mutable std::mutex mutex;
	std::condition_variable woken;
	std::vector<FisheyeFrame> kept;
	double spacing_s = 0.25;
	std::shared_ptr<const FoundRoom> last;
	uint64_t mesh_version = 0;
};

} // namespace roomprobe
