#include "capture/capture_sources.h"

#include "aravis/aravis_camera.h"
#include "capture/pixel_formats.h"
#include "openni2/openni2_device.h"

#include <opencv2/imgproc.hpp>
// The shipped addon is built without OpenCV's videoio (ROOMPROBE_NO_VIDEOIO, SConstruct's ship=yes):
// in Debian it links FFmpeg and GStreamer, over a hundred libraries to bundle for one backend.
#ifndef ROOMPROBE_NO_VIDEOIO
#include <opencv2/videoio.hpp>
#endif

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>

namespace roomprobe::drivers {

namespace {

constexpr double NO_VALUE = std::numeric_limits<double>::quiet_NaN();

std::string size_text(int p_width, int p_height) {
	return std::to_string(p_width) + "x" + std::to_string(p_height);
}

// Seconds since p_arrived (when the driver handed the frame over).
double seconds_since(std::chrono::steady_clock::time_point p_arrived) {
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - p_arrived).count();
}

GrabOutcome outcome(GrabOutcome::Kind p_kind, std::string p_error) {
	GrabOutcome result;
	result.kind = p_kind;
	result.error = std::move(p_error);
	return result;
}

// ---------------------------------------------------------------- RGB-D: OpenNI2

class OpenNI2RgbdSource : public CaptureSource {
public:
	explicit OpenNI2RgbdSource(const RgbdSourceSettings &p_settings) :
			settings(p_settings) {}

	std::string name() const override {
		return "OpenNI2 device '" + (settings.uri.empty() ? std::string("(first found)") : settings.uri) + "'";
	}

	DriverStatus open() override {
		close();
		std::string uri = settings.uri;
		if (uri.empty()) {
			DriverResult<std::vector<DeviceInfo>> listed = list_openni2_devices();
			if (!listed.ok()) {
				return { name() + ": " + listed.error };
			}
			if (listed.value.empty()) {
				return { name() + ": no depth camera found (none plugged in, or no permission on its USB device)" };
			}
			uri = listed.value.front().id;
		}
		DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(uri);
		if (!opened.ok()) {
			return { opened.error };
		}
		if (!opened.value->has_depth() || !opened.value->has_color()) {
			return { name() + ": needs both a depth and a colour stream (it has " + (opened.value->has_depth() ? "depth" : "colour") + " only)" };
		}
		if (!opened.value->is_file() && !opened.value->is_depth_registered()) {
			return { name() + ": cannot register depth to colour (OpenNI2's IMAGE_REGISTRATION_DEPTH_TO_COLOR); RoomProbe needs registered depth" };
		}
		device = std::move(opened.value);
		return {};
	}

	GrabOutcome grab(int p_timeout_ms) override {
		if (!device) {
			return outcome(GrabOutcome::Lost, name() + ": not open");
		}
		DriverResult<RgbdGrab> grabbed = device->grab(p_timeout_ms);
		const auto arrived = std::chrono::steady_clock::now();
		if (!grabbed.ok()) {
			return outcome(device->is_disconnected() ? GrabOutcome::Lost : GrabOutcome::Timeout, grabbed.error);
		}
		const DepthFrame &depth = grabbed.value.depth;
		const ColorFrame &color = grabbed.value.color;
		if (depth.width != color.width || depth.height != color.height) {
			return outcome(GrabOutcome::Lost, name() + ": depth is " + size_text(depth.width, depth.height) + " and colour " +
							size_text(color.width, color.height) + "; registered depth needs one size");
		}
		const std::string wrong = check_size(name(), "RGB-D", color.width, color.height, settings.width, settings.height);
		if (!wrong.empty()) {
			return outcome(GrabOutcome::Lost, wrong);
		}
		GrabOutcome result;
		result.kind = GrabOutcome::Frame;
		CapturedFrame &frame = result.frame;
		frame.is_rgbd = true;
		frame.rgbd.capture.device_time_s = double(depth.timestamp_ns) * 1e-9;
		frame.rgbd.capture.device_frame_id = int64_t(depth.frame_index);
		frame.rgbd.rgb = cv::Mat(color.height, color.width, CV_8UC3, const_cast<uint8_t *>(color.rgb.data())).clone();
		// OpenNI2's depth is in millimetres (the driver divides 100-um modes down).
		const cv::Mat depth_mm(depth.height, depth.width, CV_16UC1, const_cast<uint16_t *>(depth.depth_mm.data()));
		frame.rgbd.depth_m = depth_metres_from_raw(depth_mm, 0.001);
		frame.processing_s = seconds_since(arrived);
		return result;
	}

	void close() override { device.reset(); }

private:
	RgbdSourceSettings settings;
	std::unique_ptr<OpenNI2Device> device;
};

// ---------------------------------------------------------------- fisheye: Aravis

class AravisFisheyeSource : public CaptureSource {
public:
	explicit AravisFisheyeSource(const FisheyeSourceSettings &p_settings) :
			settings(p_settings) {}

	std::string name() const override {
		return "Aravis device '" + (settings.device.empty() ? std::string("(first found)") : settings.device) + "'";
	}

	DriverStatus open() override {
		close();
		std::string id = settings.device;
		if (id.empty()) {
			const DriverResult<std::vector<DeviceInfo>> listed = list_aravis_devices(settings.include_fake);
			if (!listed.ok()) {
				return { name() + ": " + listed.error };
			}
			if (listed.value.empty()) {
				return { name() + ": no GigE Vision or USB3 Vision camera found" };
			}
			id = listed.value.front().id;
		}
		DriverResult<std::unique_ptr<AravisCamera>> opened = AravisCamera::open(id);
		if (!opened.ok()) {
			return { opened.error };
		}
		AravisCamera &cam = *opened.value;
		if (!settings.pixel_format.empty()) {
			const DriverStatus set = cam.set_pixel_format(settings.pixel_format);
			if (!set.ok()) {
				return set;
			}
		}
		const std::string format = cam.get_pixel_format();
		if (!is_supported_pixel_format(format)) {
			return { name() + ": pixel format " + format + " is not supported; set pixel_format to Mono8, RGB8 or an 8-bit Bayer format" };
		}
		const DriverStatus automatic = cam.set_auto_exposure(settings.auto_exposure);
		if (!automatic.ok()) {
			return automatic;
		}
		if (!settings.auto_exposure) {
			if (std::isfinite(settings.exposure_us)) {
				const DriverStatus set = cam.set_exposure_time_us(settings.exposure_us);
				if (!set.ok()) {
					return set;
				}
			}
			if (std::isfinite(settings.gain)) {
				const DriverStatus set = cam.set_gain(settings.gain);
				if (!set.ok()) {
					return set;
				}
			}
		}
		has_exposure = cam.has_exposure_time();
		has_gain = cam.has_gain();
		camera = std::move(opened.value);
		return {};
	}

	GrabOutcome grab(int p_timeout_ms) override {
		if (!camera) {
			return outcome(GrabOutcome::Lost, name() + ": not open");
		}
		DriverResult<CameraFrame> grabbed = camera->grab(p_timeout_ms);
		const auto arrived = std::chrono::steady_clock::now();
		if (!grabbed.ok()) {
			return outcome(camera->is_connection_lost() ? GrabOutcome::Lost : GrabOutcome::Timeout, grabbed.error);
		}
		const CameraFrame &raw = grabbed.value;
		const std::string wrong = check_size(name(), "fisheye", raw.width, raw.height, settings.width, settings.height);
		if (!wrong.empty()) {
			return outcome(GrabOutcome::Lost, wrong);
		}
		std::string error;
		cv::Mat image = camera_frame_to_image(raw, &error);
		if (image.empty()) {
			return outcome(GrabOutcome::Lost, name() + ": " + error);
		}
		GrabOutcome result;
		result.kind = GrabOutcome::Frame;
		CapturedFrame &frame = result.frame;
		frame.fisheye.image = std::move(image);
		frame.fisheye.capture.device_time_s = double(raw.timestamp_ns) * 1e-9;
		frame.fisheye.capture.device_frame_id = int64_t(raw.frame_id);
		// Read after the frame: with auto-exposure on, the value that made it (the camera changes
		// it between frames, so this can be one frame late; chunk data would be exact).
		if (has_exposure) {
			DriverResult<double> exposure = camera->get_exposure_time_us();
			frame.fisheye.capture.exposure_us = exposure.ok() ? exposure.value : NO_VALUE;
		}
		if (has_gain) {
			DriverResult<double> gain = camera->get_gain();
			frame.fisheye.capture.gain = gain.ok() ? gain.value : NO_VALUE;
		}
		frame.processing_s = seconds_since(arrived);
		return result;
	}

	void close() override { camera.reset(); }

private:
	FisheyeSourceSettings settings;
	std::unique_ptr<AravisCamera> camera;
	bool has_exposure = false;
	bool has_gain = false;
};

// ---------------------------------------------------------------- fisheye: UVC (V4L2)

#ifndef ROOMPROBE_NO_VIDEOIO
class UvcFisheyeSource : public CaptureSource {
public:
	explicit UvcFisheyeSource(const FisheyeSourceSettings &p_settings) :
			settings(p_settings) {}

	std::string name() const override {
		return "UVC camera '" + (settings.device.empty() ? std::string("/dev/video0") : settings.device) + "'";
	}

	DriverStatus open() override {
		close();
		const std::string device = settings.device.empty() ? "/dev/video0" : settings.device;
		const bool index = !device.empty() && device.find_first_not_of("0123456789") == std::string::npos;
		is_file = !index && device.rfind("/dev/", 0) != 0;
		std::error_code exists_error;
		if (is_file && !std::filesystem::exists(device, exists_error)) {
			return { name() + ": no such video file or device node" };
		}
		auto opened = std::make_unique<cv::VideoCapture>();
		const bool ok = index ? opened->open(std::stoi(device), cv::CAP_V4L2) : opened->open(device, is_file ? cv::CAP_ANY : cv::CAP_V4L2);
		if (!ok || !opened->isOpened()) {
			return { name() + (is_file ? ": OpenCV cannot play this video file (missing, or a codec OpenCV lacks)" : ": cannot open it through V4L2 (not plugged in, not a capture device, or no permission)") };
		}
		if (settings.width > 0 && settings.height > 0 && !is_file) {
			opened->set(cv::CAP_PROP_FRAME_WIDTH, settings.width);
			opened->set(cv::CAP_PROP_FRAME_HEIGHT, settings.height);
		}
		if (!is_file) {
			// V4L2's auto exposure: 3 is aperture priority (auto), 1 manual.
			opened->set(cv::CAP_PROP_AUTO_EXPOSURE, settings.auto_exposure ? 3 : 1);
			if (!settings.auto_exposure && std::isfinite(settings.exposure_us)) {
				opened->set(cv::CAP_PROP_EXPOSURE, settings.exposure_us / 100.0); // V4L2 counts 100 us units
			}
			if (!settings.auto_exposure && std::isfinite(settings.gain)) {
				opened->set(cv::CAP_PROP_GAIN, settings.gain);
			}
		}
		const double fps = opened->get(cv::CAP_PROP_FPS);
		frame_period_s = is_file && std::isfinite(fps) && fps > 0.0 ? 1.0 / fps : 0.0;
		next_frame = std::chrono::steady_clock::now();
		capture = std::move(opened);
		return {};
	}

	GrabOutcome grab(int p_timeout_ms) override {
		if (!capture) {
			return outcome(GrabOutcome::Lost, name() + ": not open");
		}
		if (frame_period_s > 0.0) {
			// A file plays at its frame rate, as a camera would deliver it.
			const auto now = std::chrono::steady_clock::now();
			if (next_frame > now) {
				const auto limit = now + std::chrono::milliseconds(p_timeout_ms);
				std::this_thread::sleep_until(std::min(next_frame, limit));
				if (next_frame > limit) {
					return outcome(GrabOutcome::Timeout, "");
				}
			}
			next_frame += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(frame_period_s));
		}
		cv::Mat bgr;
		const bool read = capture->read(bgr);
		const auto arrived = std::chrono::steady_clock::now();
		if (!read || bgr.empty()) {
			if (is_file) {
				std::this_thread::sleep_for(std::chrono::milliseconds(p_timeout_ms));
				return outcome(GrabOutcome::Timeout, name() + ": end of the video");
			}
			return outcome(GrabOutcome::Lost, name() + ": no frame (unplugged?)");
		}
		const std::string wrong = check_size(name(), "fisheye", bgr.cols, bgr.rows, settings.width, settings.height);
		if (!wrong.empty()) {
			return outcome(GrabOutcome::Lost, wrong);
		}
		GrabOutcome result;
		result.kind = GrabOutcome::Frame;
		CapturedFrame &frame = result.frame;
		if (bgr.channels() == 1) {
			frame.fisheye.image = bgr;
		} else {
			cv::cvtColor(bgr, frame.fisheye.image, cv::COLOR_BGR2RGB);
		}
		frame.fisheye.capture.device_time_s = capture->get(cv::CAP_PROP_POS_MSEC) * 1e-3;
		frame.fisheye.capture.device_frame_id = frame_count++;
		if (!is_file) {
			frame.fisheye.capture.exposure_us = capture->get(cv::CAP_PROP_EXPOSURE) * 100.0;
			frame.fisheye.capture.gain = capture->get(cv::CAP_PROP_GAIN);
		}
		frame.processing_s = seconds_since(arrived);
		return result;
	}

	void close() override { capture.reset(); }

private:
	FisheyeSourceSettings settings;
	std::unique_ptr<cv::VideoCapture> capture;
	bool is_file = false;
	double frame_period_s = 0.0;
	std::chrono::steady_clock::time_point next_frame;
	int64_t frame_count = 0;
};

#else
// The addon's build: a source that says what this build lacks, and what to use instead.
class UnavailableSource : public CaptureSource {
public:
	UnavailableSource(std::string p_name, std::string p_why) :
			source_name(std::move(p_name)), why(std::move(p_why)) {}
	std::string name() const override { return source_name; }
	DriverStatus open() override { return { source_name + ": " + why }; }
	GrabOutcome grab(int) override { return outcome(GrabOutcome::Lost, source_name + ": not open"); }
	void close() override {}

private:
	std::string source_name;
	std::string why;
};
#endif

} // namespace

std::string check_size(const std::string &p_name, const char *p_what, int p_width, int p_height, int p_rig_width, int p_rig_height) {
	if ((p_rig_width <= 0 && p_rig_height <= 0) || (p_width == p_rig_width && p_height == p_rig_height)) {
		return "";
	}
	return p_name + ": " + p_what + " frames are " + size_text(p_width, p_height) + ", the rig file says " +
			size_text(p_rig_width, p_rig_height) + " (choose that mode, or calibrate the rig for this one)";
}

std::unique_ptr<CaptureSource> make_openni2_rgbd_source(const RgbdSourceSettings &p_settings) {
	return std::make_unique<OpenNI2RgbdSource>(p_settings);
}

std::unique_ptr<CaptureSource> make_aravis_fisheye_source(const FisheyeSourceSettings &p_settings) {
	return std::make_unique<AravisFisheyeSource>(p_settings);
}

std::unique_ptr<CaptureSource> make_uvc_fisheye_source(const FisheyeSourceSettings &p_settings) {
#ifndef ROOMPROBE_NO_VIDEOIO
	return std::make_unique<UvcFisheyeSource>(p_settings);
#else
	return std::make_unique<UnavailableSource>("UVC camera '" + (p_settings.device.empty() ? std::string("/dev/video0") : p_settings.device) + "'",
			"this build of RoomProbe has no UVC backend (the packaged addon leaves out OpenCV's videoio and its FFmpeg and "
			"GStreamer libraries); use an Aravis (GigE or USB3 Vision) fisheye, or build RoomProbe from source with ./roomprobe build");
#endif
}

} // namespace roomprobe::drivers
