#include "live_rig.h"

namespace roomprobe::drivers {

namespace {

size_t slot(RecordingStream p_stream) {
	return p_stream == RecordingStream::Rgbd ? 0 : 1;
}

} // namespace

Rig live_capture_rig(const Rig &p_rig) {
	Rig rig = p_rig;
	rig.fisheye_time_offset_s = 0.0;
	return rig;
}

LiveRig::~LiveRig() {
	stop();
	stop_recording();
}

std::string LiveRig::start(const Rig &p_rig, const LiveRigSettings &p_settings, FrameSink p_on_frame, StateSink p_on_state) {
	stop();
	rig = live_capture_rig(p_rig);
	on_frame = std::move(p_on_frame);
	const bool use_fisheye = p_settings.use_fisheye && rig.has_fisheye();
	if (!p_settings.use_rgbd && !use_fisheye) {
		return p_settings.use_fisheye ? "nothing to capture: the RGB-D camera is off and the rig has no fisheye"
									  : "nothing to capture: both the RGB-D camera and the fisheye are off";
	}
	const auto state_sink = [p_on_state](RecordingStream p_stream) -> DeviceCapture::StateSink {
		if (!p_on_state) {
			return nullptr;
		}
		return [p_on_state, p_stream](const DeviceStatus &p_status) { p_on_state(p_stream, p_status); };
	};
	const auto frame_sink = [this](CapturedFrame &&p_frame) { deliver(std::move(p_frame)); };
	if (p_settings.use_rgbd) {
		RgbdSourceSettings settings = p_settings.rgbd;
		settings.width = rig.rgb.width;
		settings.height = rig.rgb.height;
		DeviceCaptureOptions options = p_settings.capture;
		options.latency_s = rig.rgbd_latency_s;
		captures[0] = std::make_unique<DeviceCapture>(make_openni2_rgbd_source(settings), options, frame_sink, state_sink(RecordingStream::Rgbd));
	}
	if (use_fisheye) {
		FisheyeSourceSettings settings = p_settings.fisheye;
		settings.width = rig.fisheye.width;
		settings.height = rig.fisheye.height;
		DeviceCaptureOptions options = p_settings.capture;
		options.latency_s = rig.fisheye_latency_s;
		std::unique_ptr<CaptureSource> source;
		switch (p_settings.fisheye_backend) {
			case FisheyeBackend::Aravis:
				source = make_aravis_fisheye_source(settings);
				break;
			case FisheyeBackend::Uvc:
				source = make_uvc_fisheye_source(settings);
				break;
			case FisheyeBackend::Pushed:
				if (!p_settings.pushed_fisheye) {
					stop();
					return "the fisheye backend takes pushed frames, but nothing pushes them (LiveRigSettings::pushed_fisheye is empty)";
				}
				source = make_pushed_fisheye_source(p_settings.pushed_fisheye, settings.width, settings.height);
				break;
		}
		captures[1] = std::make_unique<DeviceCapture>(std::move(source), options, frame_sink, state_sink(RecordingStream::Fisheye));
	}
	for (std::unique_ptr<DeviceCapture> &capture : captures) {
		const std::string error = capture ? capture->start() : std::string();
		if (!error.empty()) {
			stop();
			return error;
		}
	}
	return std::string();
}

void LiveRig::stop() {
	for (std::unique_ptr<DeviceCapture> &capture : captures) {
		if (capture) {
			capture->stop();
			capture.reset();
		}
	}
}

bool LiveRig::is_running() const {
	return (captures[0] && captures[0]->is_running()) || (captures[1] && captures[1]->is_running());
}

bool LiveRig::uses(RecordingStream p_stream) const {
	return captures[slot(p_stream)] != nullptr;
}

DeviceStatus LiveRig::status(RecordingStream p_stream) const {
	const std::unique_ptr<DeviceCapture> &capture = captures[slot(p_stream)];
	return capture ? capture->status() : DeviceStatus();
}

std::string LiveRig::device_name(RecordingStream p_stream) const {
	const std::unique_ptr<DeviceCapture> &capture = captures[slot(p_stream)];
	return capture ? capture->name() : std::string();
}

void LiveRig::deliver(CapturedFrame &&p_frame) {
	std::shared_ptr<RecordingQueue> queue;
	{
		std::lock_guard lock(recording_mutex);
		queue = recording;
	}
	if (queue) {
		// The queue keeps its own copy of the pixels: the sink below takes the frame.
		if (p_frame.is_rgbd) {
			queue->push_rgbd(p_frame.rgbd);
		} else {
			queue->push_fisheye(p_frame.fisheye);
		}
	}
	if (on_frame) {
		on_frame(std::move(p_frame));
	}
}

RecordingStatus LiveRig::start_recording(const std::string &p_folder, const RoomInfo *p_room, const RecordingQueueOptions &p_options) {
	RecordingStatus status;
	if (!captures[0] && !captures[1]) {
		status.error = p_folder + ": the live rig is not capturing; start it before recording";
		return status;
	}
	if (is_recording()) {
		status.error = p_folder + ": already recording into " + recording_status().folder + "; stop that recording first";
		return status;
	}
	auto queue = std::make_shared<RecordingQueue>();
	status = queue->open(p_folder, rig, p_room, p_options);
	if (status.ok) {
		std::lock_guard lock(recording_mutex);
		recording = queue;
	}
	return status;
}

RecordingStatus LiveRig::stop_recording() {
	std::shared_ptr<RecordingQueue> queue;
	{
		std::lock_guard lock(recording_mutex);
		queue.swap(recording);
	}
	RecordingStatus status;
	if (!queue) {
		status.ok = true;
		return status;
	}
	status = queue->close(); // a capture thread that took the queue a moment ago is refused: closed
	std::lock_guard lock(recording_mutex);
	last_recording = queue->status();
	return status;
}

bool LiveRig::is_recording() const {
	std::lock_guard lock(recording_mutex);
	return recording != nullptr;
}

RecordingQueueStatus LiveRig::recording_status() const {
	std::lock_guard lock(recording_mutex);
	return recording ? recording->status() : last_recording;
}

} // namespace roomprobe::drivers
