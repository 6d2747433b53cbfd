#include "capture/pushed_camera.h"

#include "capture/capture_sources.h"

#include <algorithm>
#include <chrono>

namespace roomprobe::drivers {

std::string PushedFrames::name() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return camera_name;
}

void PushedFrames::set_name(std::string p_name) {
	const std::lock_guard<std::mutex> lock(mutex);
	camera_name = std::move(p_name);
}

void PushedFrames::push(cv::Mat p_image, uint64_t p_arrival_ns, int64_t p_frame_id) {
	{
		const std::lock_guard<std::mutex> lock(mutex);
		image = std::move(p_image);
		arrival_ns = p_arrival_ns;
		frame_id = p_frame_id;
		waiting = true;
		absent.clear();
		pushed++;
	}
	arrived.notify_one();
}

void PushedFrames::set_absent(std::string p_reason) {
	const std::lock_guard<std::mutex> lock(mutex);
	absent = std::move(p_reason);
	if (!absent.empty()) {
		waiting = false;
		image.release();
	}
}

uint64_t PushedFrames::pushed_count() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return pushed;
}

std::string PushedFrames::absent_reason() const {
	const std::lock_guard<std::mutex> lock(mutex);
	return absent;
}

bool PushedFrames::take(int p_timeout_ms, cv::Mat *r_image, uint64_t *r_arrival_ns, int64_t *r_frame_id) {
	std::unique_lock<std::mutex> lock(mutex);
	if (!arrived.wait_for(lock, std::chrono::milliseconds(p_timeout_ms), [this] { return waiting; })) {
		return false;
	}
	*r_image = std::move(image);
	*r_arrival_ns = arrival_ns;
	*r_frame_id = frame_id;
	waiting = false;
	return true;
}

void PushedFrames::drop_waiting() {
	const std::lock_guard<std::mutex> lock(mutex);
	waiting = false;
	image.release();
}

namespace {

class PushedFisheyeSource : public CaptureSource {
public:
	PushedFisheyeSource(std::shared_ptr<PushedFrames> p_frames, int p_width, int p_height) :
			frames(std::move(p_frames)), width(p_width), height(p_height) {}

	std::string name() const override { return frames->name(); }

	// Fails while the host says its camera is absent; a frame pushed before the capture started is stale.
	DriverStatus open() override {
		frames->drop_waiting();
		const std::string absent = frames->absent_reason();
		return { absent.empty() ? std::string() : name() + ": " + absent };
	}

	GrabOutcome grab(int p_timeout_ms) override {
		GrabOutcome result;
		cv::Mat image;
		uint64_t arrival_ns = 0;
		int64_t frame_id = -1;
		if (!frames->take(p_timeout_ms, &image, &arrival_ns, &frame_id)) {
			const std::string absent = frames->absent_reason();
			result.kind = absent.empty() ? GrabOutcome::Timeout : GrabOutcome::Lost;
			result.error = name() + ": " + (absent.empty() ? "no new frame" : absent);
			return result;
		}
		if (image.empty() || (image.type() != CV_8UC3 && image.type() != CV_8UC1)) {
			result.kind = GrabOutcome::Lost;
			result.error = name() + ": a frame that is not 8-bit RGB or grey";
			return result;
		}
		const std::string wrong = check_size(name(), "fisheye", image.cols, image.rows, width, height);
		if (!wrong.empty()) {
			result.kind = GrabOutcome::Lost;
			result.error = wrong;
			return result;
		}
		result.kind = GrabOutcome::Frame;
		result.frame.fisheye.image = image;
		result.frame.fisheye.capture.device_frame_id = frame_id;
		// The frame arrived when the host stamped it, not when this thread took it.
		const uint64_t now_ns = monotonic_clock_ns();
		result.frame.processing_s = double(now_ns - std::min(arrival_ns, now_ns)) * 1e-9;
		return result;
	}

	void close() override {}

private:
	std::shared_ptr<PushedFrames> frames;
	int width = 0;
	int height = 0;
};

} // namespace

std::unique_ptr<CaptureSource> make_pushed_fisheye_source(std::shared_ptr<PushedFrames> p_frames, int p_width, int p_height) {
	return std::make_unique<PushedFisheyeSource>(std::move(p_frames), p_width, p_height);
}

} // namespace roomprobe::drivers
