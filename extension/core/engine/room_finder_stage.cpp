#include "room_finder_stage.h"

#include <algorithm>
#include <chrono>

namespace roomprobe {

void RoomFinderStage::reset() {
	const std::lock_guard<std::mutex> lock(mutex);
	kept.clear();
	spacing_s = 0.25;
	last.reset();
	mesh_version = 0;
}

void RoomFinderStage::keep_view(const FisheyeFrame &p_frame, size_t p_max_views) {
	if (p_frame.image.empty() || p_max_views == 0) {
		return;
	}
	const std::lock_guard<std::mutex> lock(mutex);
	if (!kept.empty() && p_frame.timestamp_s - kept.back().timestamp_s < spacing_s) {
		return;
	}
	FisheyeFrame view = p_frame;
	view.image = p_frame.image.clone(); // a driver may reuse its buffer
	view.saturated.release();
	kept.push_back(std::move(view));
	if (kept.size() >= 2 * p_max_views) {
		std::vector<FisheyeFrame> thinned;
		for (size_t i = 0; i < kept.size(); i += 2) {
			thinned.push_back(std::move(kept[i]));
		}
		kept = std::move(thinned);
		spacing_s *= 2.0;
	}
}

std::vector<FisheyeFrame> RoomFinderStage::views() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return kept;
}

std::shared_ptr<const FoundRoom> RoomFinderStage::estimate(SweepObservations p_observed, bool p_has_dense, size_t p_fused_frames, uint64_t p_mesh_version,
		const RoomEstimationOptions &p_options, std::chrono::steady_clock::time_point p_start) {
	auto found = std::make_shared<FoundRoom>();
	found->fisheye_views = p_observed.fisheye_views.size();
	if (!p_has_dense) {
		found->result.estimate.message = "no dense model: finding the room needs dense SLAM";
	} else {
		found->result = find_room_from_sweep(p_observed, p_options);
	}
	found->samples = std::move(p_observed.samples);
	found->fused_frames = p_fused_frames;
	found->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - p_start).count();
	return publish(std::move(found), p_mesh_version);
}

std::shared_ptr<const FoundRoom> RoomFinderStage::publish_failure(const std::string &p_message) {
	auto failed = std::make_shared<FoundRoom>();
	failed->result.estimate.message = p_message;
	const std::lock_guard<std::mutex> lock(mutex);
	failed->version = last ? last->version + 1 : 1;
	last = failed;
	return failed;
}

std::shared_ptr<const FoundRoom> RoomFinderStage::publish(std::shared_ptr<FoundRoom> p_found, uint64_t p_mesh_version) {
	const std::lock_guard<std::mutex> lock(mutex);
	p_found->version = last ? last->version + 1 : 1;
	mesh_version = p_mesh_version;
	last = p_found;
	return last;
}

std::shared_ptr<const FoundRoom> RoomFinderStage::found() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return last;
}

uint64_t RoomFinderStage::estimated_mesh_version() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return mesh_version;
}

bool RoomFinderStage::wait(double p_interval_s, const std::atomic<bool> &p_stopping) {
	std::unique_lock<std::mutex> lock(mutex);
	woken.wait_for(lock, std::chrono::duration<double>(std::max(p_interval_s, 0.1)), [&p_stopping] { return bool(p_stopping); });
	return !p_stopping;
}

void RoomFinderStage::wake() {
	const std::lock_guard<std::mutex> lock(mutex);
	woken.notify_all();
}

} // namespace roomprobe
