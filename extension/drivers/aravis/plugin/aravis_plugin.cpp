// The Aravis plugin (libroomprobe_aravis.so): GenICam cameras through Aravis 0.8, built as a
// library of its own so that Aravis, GLib, libxml2 and ICU load only when an Aravis camera is
// listed or opened (aravis/aravis_loader.cpp), and ship apart from the addon (docs/addon.md).
#include "aravis/aravis_plugin_api.h"

#include "capture/capture_clock.h"

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>

namespace roomprobe::drivers {

namespace {

// Aravis hands out owned GObject references; unique_ptr gives them back.
struct GObjectUnref {
	void operator()(gpointer p_object) const { g_object_unref(p_object); }
};
template <class T>
using GObjectPtr = std::unique_ptr<T, GObjectUnref>;

// Receives the GError of one Aravis call (pass out()), frees it when done.
class ErrorSlot {
public:
	ErrorSlot() = default;
	ErrorSlot(const ErrorSlot &) = delete;
	ErrorSlot &operator=(const ErrorSlot &) = delete;
	~ErrorSlot() { clear(); }

	GError **out() {
		clear();
		return &error;
	}
	bool failed() const { return error != nullptr; }
	bool is(GQuark p_domain, int p_code) const { return g_error_matches(error, p_domain, p_code); }
	std::string message() const { return error ? error->message : ""; }

private:
	void clear() { g_clear_error(&error); }

	GError *error = nullptr;
};

// A streaming camera keeps this many buffers queued: enough that one slow
// grab() does not make the camera drop frames, few enough to stay current.
constexpr int STREAM_BUFFER_COUNT = 4;

// Aravis' interface switches and device list are process-wide.
std::mutex device_list_mutex;

std::string text(const char *p_text) {
	return p_text ? p_text : "";
}

std::string device_name(const std::string &p_device_id) {
	return "Aravis device '" + p_device_id + "'";
}

std::vector<DeviceInfo> list_devices_locked(bool p_include_fake) {
	if (p_include_fake) {
		arv_enable_interface("Fake");
	} else {
		arv_disable_interface("Fake");
	}
	arv_update_device_list();
	std::vector<DeviceInfo> devices;
	const unsigned int count = arv_get_n_devices();
	for (unsigned int i = 0; i < count; i++) {
		devices.push_back({ "aravis", text(arv_get_device_id(i)), text(arv_get_device_vendor(i)),
				text(arv_get_device_model(i)), text(arv_get_device_serial_nbr(i)), {} });
	}
	return devices;
}

const char *buffer_status_name(ArvBufferStatus p_status) {
	switch (p_status) {
		case ARV_BUFFER_STATUS_SUCCESS:
			return "success";
		case ARV_BUFFER_STATUS_CLEARED:
			return "cleared";
		case ARV_BUFFER_STATUS_TIMEOUT:
			return "timed out before all packets arrived";
		case ARV_BUFFER_STATUS_MISSING_PACKETS:
			return "missing packets";
		case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
			return "wrong packet id";
		case ARV_BUFFER_STATUS_SIZE_MISMATCH:
			return "image larger than the buffer";
		case ARV_BUFFER_STATUS_FILLING:
			return "still filling";
		case ARV_BUFFER_STATUS_ABORTED:
			return "aborted";
#if ARAVIS_CHECK_VERSION(0, 8, 27) // not in 0.8.26 (Debian 12)
		case ARV_BUFFER_STATUS_PAYLOAD_NOT_SUPPORTED:
			return "payload not supported";
#endif
		default:
			return "unknown status";
	}
}

// Aravis' heartbeat thread calls this when the camera stops answering. The
// closure owns a reference to the flag, so it stays valid whatever outlives what.
void on_control_lost(ArvDevice *, gpointer p_flag) {
	(*static_cast<std::shared_ptr<std::atomic<bool>> *>(p_flag))->store(true);
}

void release_control_lost_flag(gpointer p_flag, GClosure *) {
	delete static_cast<std::shared_ptr<std::atomic<bool>> *>(p_flag);
}

} // namespace

struct State {
	std::string name; // "Aravis device 'id'", the prefix of every message.
	DeviceInfo info;
	int sensor_width = 0;
	int sensor_height = 0;
	GObjectPtr<ArvCamera> camera;
	GObjectPtr<ArvStream> stream; // Set while acquiring.
	std::string stream_pixel_format; // The format the running stream was started with.
	std::shared_ptr<std::atomic<bool>> control_lost = std::make_shared<std::atomic<bool>>(false);

	std::string lost_message() const {
		return name + ": connection lost (unplugged, powered off or taken by another program); open it again";
	}

	DriverStatus start_stream() {
		ErrorSlot error;
		ArvCamera *cam = camera.get();
		const std::string format = text(arv_camera_get_pixel_format_as_string(cam, error.out()));
		if (error.failed()) {
			return { name + ": cannot read the pixel format: " + error.message() };
		}
		arv_camera_set_acquisition_mode(cam, ARV_ACQUISITION_MODE_CONTINUOUS, error.out());
		if (error.failed()) {
			return { name + ": cannot select continuous acquisition: " + error.message() };
		}
		const guint payload = arv_camera_get_payload(cam, error.out());
		if (error.failed() || payload == 0) {
			return { name + ": cannot read the frame size (payload): " + (error.failed() ? error.message() : "0 bytes") };
		}
		GObjectPtr<ArvStream> new_stream(arv_camera_create_stream(cam, nullptr, nullptr, error.out()));
		if (!new_stream) {
			return { name + ": cannot create a stream: " + (error.failed() ? error.message() : "no reason given") };
		}
		for (int i = 0; i < STREAM_BUFFER_COUNT; i++) {
			arv_stream_push_buffer(new_stream.get(), arv_buffer_new_allocate(payload));
		}
		arv_camera_start_acquisition(cam, error.out());
		if (error.failed()) {
			return { name + ": cannot start acquisition: " + error.message() };
		}
		stream = std::move(new_stream);
		stream_pixel_format = format;
		return {};
	}

	~State() {
		if (stream && !control_lost->load()) {
			// A lost camera would only time out on the stop command.
			ErrorSlot error;
			arv_camera_stop_acquisition(camera.get(), error.out());
		}
		stream.reset(); // Joins the receiving thread; the buffers go with it.
		camera.reset();
	}
};

// Hands a popped buffer back to the stream's pool however grab() leaves.
class BufferLoan {
public:
	BufferLoan(ArvStream *p_stream, ArvBuffer *p_buffer) :
			stream(p_stream), buffer(p_buffer) {}
	BufferLoan(const BufferLoan &) = delete;
	BufferLoan &operator=(const BufferLoan &) = delete;
	~BufferLoan() { arv_stream_push_buffer(stream, buffer); }

	ArvStream *const stream;
	ArvBuffer *const buffer;
};

// AravisCamera on Aravis' objects: the one implementation, made only by open_camera().
class AravisPluginCamera final : public AravisCamera {
public:
	explicit AravisPluginCamera(std::unique_ptr<State> p_state) :
			state(std::move(p_state)) {}

	DriverResult<CameraFrame> grab(int p_timeout_ms) override;
	const std::string &get_device_id() const override;
	DeviceInfo get_info() const override;
	int get_sensor_width() const override;
	int get_sensor_height() const override;
	int get_width() const override;
	int get_height() const override;
	std::string get_pixel_format() const override;
	bool is_streaming() const override;
	bool is_connection_lost() const override;
	std::vector<std::string> get_available_pixel_formats() const override;
	DriverStatus set_pixel_format(const std::string &p_format) override;
	DriverStatus set_auto_exposure(bool p_on) override;
	bool has_exposure_time() const override;
	DriverResult<double> get_exposure_time_us() const override;
	DriverStatus set_exposure_time_us(double p_exposure_us) override;
	bool has_gain() const override;
	DriverResult<double> get_gain() const override;
	DriverStatus set_gain(double p_gain) override;

private:
	std::unique_ptr<State> state;
};

std::vector<DeviceInfo> list_cameras(bool p_include_fake) {
	std::lock_guard lock(device_list_mutex);
	return list_devices_locked(p_include_fake);
}

DriverResult<std::unique_ptr<AravisCamera>> open_camera(const std::string &p_device_id) {
	using Result = DriverResult<std::unique_ptr<AravisCamera>>;
	const std::string name = device_name(p_device_id);
	if (p_device_id.empty()) {
		// Aravis would open the first camera it finds: never what a rig wants.
		return Result::failure(name + ": empty device id (list_aravis_devices() gives the ids)");
	}
	const bool fake = p_device_id.rfind("Fake_", 0) == 0;
	ErrorSlot error;
	GObjectPtr<ArvCamera> camera;
	{
		std::lock_guard lock(device_list_mutex);
		if (fake) {
			arv_enable_interface("Fake");
		}
		camera.reset(arv_camera_new(p_device_id.c_str(), error.out()));
		if (!camera) {
			if (!error.failed() || error.is(ARV_DEVICE_ERROR, ARV_DEVICE_ERROR_NOT_FOUND)) {
				return Result::failure(name + ": not found (" + describe_listed(list_devices_locked(fake)) + ")");
			}
			return Result::failure(name + ": cannot open: " + error.message());
		}
	}

	auto state = std::make_unique<State>();
	state->name = name;
	ArvCamera *cam = camera.get();
	state->info = { "aravis", p_device_id, text(arv_camera_get_vendor_name(cam, error.out())),
		text(arv_camera_get_model_name(cam, error.out())), text(arv_camera_get_device_serial_number(cam, error.out())), {} };
	arv_camera_get_sensor_size(cam, &state->sensor_width, &state->sensor_height, error.out());
	if (error.failed()) {
		return Result::failure(name + ": cannot read the sensor size: " + error.message());
	}
	g_signal_connect_data(arv_camera_get_device(cam), "control-lost", G_CALLBACK(on_control_lost),
			new std::shared_ptr<std::atomic<bool>>(state->control_lost), release_control_lost_flag, GConnectFlags(0));
	state->camera = std::move(camera);
	return Result::success(std::unique_ptr<AravisCamera>(new AravisPluginCamera(std::move(state))));
}

DriverResult<CameraFrame> AravisPluginCamera::grab(int p_timeout_ms) {
	using Result = DriverResult<CameraFrame>;
	State &s = *state;
	if (s.control_lost->load()) {
		return Result::failure(s.lost_message());
	}
	if (!s.stream) {
		const DriverStatus started = s.start_stream();
		if (!started.ok()) {
			return Result::failure(started.error);
		}
	}

	using Clock = std::chrono::steady_clock;
	const Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(std::max(p_timeout_ms, 0));
	std::string last_problem;
	for (bool first = true;; first = false) {
		const auto left_us = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
		if (left_us <= 0 && !first) {
			break;
		}
		ArvBuffer *buffer = arv_stream_timeout_pop_buffer(s.stream.get(), guint64(std::max<int64_t>(left_us, 0)));
		if (!buffer) {
			break;
		}
		std::vector<ArvBuffer *> queued{ buffer };
		while (ArvBuffer *more = arv_stream_try_pop_buffer(s.stream.get())) {
			queued.push_back(more);
		}
		if (queued.size() >= size_t(STREAM_BUFFER_COUNT)) {
			// Every buffer was waiting here, so the camera had nowhere to put newer
			// frames and dropped them: these are stale. Recycle them, wait for a fresh one.
			for (ArvBuffer *stale : queued) {
				arv_stream_push_buffer(s.stream.get(), stale);
			}
			continue;
		}
		// The newest complete frame is current; older queued ones go back to the pool.
		const auto newest_complete = std::find_if(queued.rbegin(), queued.rend(),
				[](ArvBuffer *p_buffer) { return arv_buffer_get_status(p_buffer) == ARV_BUFFER_STATUS_SUCCESS; });
		buffer = newest_complete != queued.rend() ? *newest_complete : queued.back();
		for (ArvBuffer *other : queued) {
			if (other != buffer) {
				arv_stream_push_buffer(s.stream.get(), other);
			}
		}
		const BufferLoan loan(s.stream.get(), buffer);

		const ArvBufferStatus status = arv_buffer_get_status(buffer);
		if (status != ARV_BUFFER_STATUS_SUCCESS) {
			last_problem = std::string("incomplete frame (") + buffer_status_name(status) + ")";
			continue;
		}
		const ArvPixelFormat format = arv_buffer_get_image_pixel_format(buffer);
		const int bits = int(ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format));
		if (bits != 8 && bits != 24) {
			return Result::failure(s.name + ": pixel format " + s.stream_pixel_format + " has " +
					std::to_string(bits) + " bits per pixel; only 8-bit formats are supported (Mono8, Bayer*8, RGB8, BGR8)");
		}
		const int channels = bits / 8;
		const int width = arv_buffer_get_image_width(buffer);
		const int height = arv_buffer_get_image_height(buffer);
		int x_padding = 0;
		int y_padding = 0;
		arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
		size_t size = 0;
		const uint8_t *data = static_cast<const uint8_t *>(arv_buffer_get_image_data(buffer, &size));
		const size_t row_bytes = size_t(width) * size_t(channels);
		const size_t stride = row_bytes + size_t(std::max(x_padding, 0));
		if (!data || width <= 0 || height <= 0 || size < stride * size_t(height - 1) + row_bytes) {
			return Result::failure(s.name + ": frame of " + std::to_string(size) + " bytes does not hold the " +
					std::to_string(width) + "x" + std::to_string(height) + " image it announces");
		}

		CameraFrame frame;
		frame.width = width;
		frame.height = height;
		frame.channels = channels;
		frame.pixel_format = s.stream_pixel_format;
		frame.pixels.resize(row_bytes * size_t(height));
		for (int y = 0; y < height; y++) {
			std::memcpy(frame.pixels.data() + size_t(y) * row_bytes, data + size_t(y) * stride, row_bytes);
		}
		// Aravis' system timestamp is the wall clock, which can jump; the rig's clock is monotonic.
		frame.host_timestamp_ns = monotonic_clock_ns();
		const uint64_t camera_ns = arv_buffer_get_timestamp(buffer);
		frame.timestamp_ns = camera_ns ? camera_ns : frame.host_timestamp_ns;
		frame.frame_id = arv_buffer_get_frame_id(buffer);
		return Result::success(std::move(frame));
	}
	if (s.control_lost->load()) {
		return Result::failure(s.lost_message());
	}
	return Result::failure(s.name + ": no frame within " + std::to_string(p_timeout_ms) + " ms" +
			(last_problem.empty() ? std::string() : " (last one: " + last_problem + ")"));
}

const std::string &AravisPluginCamera::get_device_id() const {
	return state->info.id;
}

DeviceInfo AravisPluginCamera::get_info() const {
	return state->info;
}

int AravisPluginCamera::get_sensor_width() const {
	return state->sensor_width;
}

int AravisPluginCamera::get_sensor_height() const {
	return state->sensor_height;
}

int AravisPluginCamera::get_width() const {
	ErrorSlot error;
	int x = 0, y = 0, width = 0, height = 0;
	arv_camera_get_region(state->camera.get(), &x, &y, &width, &height, error.out());
	return width;
}

int AravisPluginCamera::get_height() const {
	ErrorSlot error;
	int x = 0, y = 0, width = 0, height = 0;
	arv_camera_get_region(state->camera.get(), &x, &y, &width, &height, error.out());
	return height;
}

std::string AravisPluginCamera::get_pixel_format() const {
	ErrorSlot error;
	return text(arv_camera_get_pixel_format_as_string(state->camera.get(), error.out()));
}

bool AravisPluginCamera::is_streaming() const {
	return state->stream != nullptr;
}

bool AravisPluginCamera::is_connection_lost() const {
	return state->control_lost->load();
}

std::vector<std::string> AravisPluginCamera::get_available_pixel_formats() const {
	ErrorSlot error;
	guint count = 0;
	const char **names = arv_camera_dup_available_pixel_formats_as_strings(state->camera.get(), &count, error.out());
	std::vector<std::string> formats;
	for (guint i = 0; names && i < count; i++) {
		formats.push_back(text(names[i]));
	}
	g_free(names); // the array only: its strings belong to the camera
	return formats;
}

DriverStatus AravisPluginCamera::set_pixel_format(const std::string &p_format) {
	const std::string what = state->name + ": cannot set the pixel format " + p_format + ": ";
	if (state->stream) {
		return { what + "the camera is streaming (set it before the first grab)" };
	}
	const std::vector<std::string> formats = get_available_pixel_formats();
	if (std::find(formats.begin(), formats.end(), p_format) == formats.end()) {
		return { what + "the camera offers " + (formats.empty() ? std::string("none it can name") : comma_list(formats)) };
	}
	ErrorSlot error;
	arv_camera_set_pixel_format_from_string(state->camera.get(), p_format.c_str(), error.out());
	if (error.failed()) {
		return { what + error.message() };
	}
	return {};
}

DriverStatus AravisPluginCamera::set_auto_exposure(bool p_on) {
	ErrorSlot error;
	ArvCamera *cam = state->camera.get();
	const bool exposure = arv_camera_is_exposure_auto_available(cam, error.out()) && !error.failed();
	const bool gain = arv_camera_is_gain_auto_available(cam, error.out()) && !error.failed();
	if (!exposure && !gain) {
		return p_on ? DriverStatus{ state->name + ": cannot turn auto-exposure on: the camera has neither ExposureAuto nor GainAuto" } : DriverStatus{};
	}
	if (exposure) {
		arv_camera_set_exposure_time_auto(cam, p_on ? ARV_AUTO_CONTINUOUS : ARV_AUTO_OFF, error.out());
		if (error.failed()) {
			return { state->name + ": cannot set ExposureAuto: " + error.message() };
		}
	}
	if (gain) {
		arv_camera_set_gain_auto(cam, p_on ? ARV_AUTO_CONTINUOUS : ARV_AUTO_OFF, error.out());
		if (error.failed()) {
			return { state->name + ": cannot set GainAuto: " + error.message() };
		}
	}
	return {};
}

bool AravisPluginCamera::has_exposure_time() const {
	ErrorSlot error;
	return arv_camera_is_exposure_time_available(state->camera.get(), error.out()) && !error.failed();
}

DriverResult<double> AravisPluginCamera::get_exposure_time_us() const {
	ErrorSlot error;
	const double exposure = arv_camera_get_exposure_time(state->camera.get(), error.out());
	if (error.failed()) {
		return DriverResult<double>::failure(state->name + ": cannot read the exposure time: " + error.message());
	}
	return DriverResult<double>::success(exposure);
}

DriverStatus AravisPluginCamera::set_exposure_time_us(double p_exposure_us) {
	ArvCamera *cam = state->camera.get();
	const std::string what = state->name + ": cannot set the exposure time to " + std::to_string(p_exposure_us) + " us: ";
	if (!has_exposure_time()) {
		return { what + "the camera has no exposure time feature" };
	}
	ErrorSlot error;
	double low = 0.0, high = 0.0;
	arv_camera_get_exposure_time_bounds(cam, &low, &high, error.out());
	if (!error.failed() && (p_exposure_us < low || p_exposure_us > high)) {
		return { what + "outside " + std::to_string(low) + " to " + std::to_string(high) + " us" };
	}
	// An auto-exposure loop would overwrite the value at once.
	if (arv_camera_is_exposure_auto_available(cam, error.out())) {
		arv_camera_set_exposure_time_auto(cam, ARV_AUTO_OFF, error.out());
	}
	arv_camera_set_exposure_time(cam, p_exposure_us, error.out());
	if (error.failed()) {
		return { what + error.message() };
	}
	return {};
}

bool AravisPluginCamera::has_gain() const {
	ErrorSlot error;
	return arv_camera_is_gain_available(state->camera.get(), error.out()) && !error.failed();
}

DriverResult<double> AravisPluginCamera::get_gain() const {
	ErrorSlot error;
	const double gain = arv_camera_get_gain(state->camera.get(), error.out());
	if (error.failed()) {
		return DriverResult<double>::failure(state->name + ": cannot read the gain: " + error.message());
	}
	return DriverResult<double>::success(gain);
}

DriverStatus AravisPluginCamera::set_gain(double p_gain) {
	ArvCamera *cam = state->camera.get();
	const std::string what = state->name + ": cannot set the gain to " + std::to_string(p_gain) + ": ";
	if (!has_gain()) {
		return { what + "the camera has no gain feature" };
	}
	ErrorSlot error;
	double low = 0.0, high = 0.0;
	arv_camera_get_gain_bounds(cam, &low, &high, error.out());
	if (!error.failed() && (p_gain < low || p_gain > high)) {
		return { what + "outside " + std::to_string(low) + " to " + std::to_string(high) };
	}
	if (arv_camera_is_gain_auto_available(cam, error.out())) {
		arv_camera_set_gain_auto(cam, ARV_AUTO_OFF, error.out());
	}
	arv_camera_set_gain(cam, p_gain, error.out());
	if (error.failed()) {
		return { what + error.message() };
	}
	return {};
}

const AravisPluginApi PLUGIN_API = { ARAVIS_PLUGIN_VERSION, __VERSION__, list_cameras, open_camera };

} // namespace roomprobe::drivers

extern "C" __attribute__((visibility("default"))) const roomprobe::drivers::AravisPluginApi *roomprobe_aravis_plugin() {
	return &roomprobe::drivers::PLUGIN_API;
}
