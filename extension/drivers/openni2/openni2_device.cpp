#include "openni2/openni2_device.h"

#include "capture/capture_clock.h"

#include <OpenNI.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

namespace roomprobe::drivers {

namespace {

namespace fs = std::filesystem;
using openni::OpenNI;

// OpenNI's extended error comes with tabs and newlines around it.
std::string extended_error() {
	std::string message = OpenNI::getExtendedError();
	const auto is_space = [](unsigned char c) { return std::isspace(c) != 0; };
	message.erase(message.begin(), std::find_if_not(message.begin(), message.end(), is_space));
	message.erase(std::find_if_not(message.rbegin(), message.rend(), is_space).base(), message.end());
	for (char &c : message) {
		c = (c == '\n' || c == '\t') ? ' ' : c;
	}
	return message.empty() ? "no reason given" : message;
}

// Keeps OpenNI initialised while any holder lives. OpenNI counts its own
// initialize/shutdown calls; this adds thread safety and a clean retry after a
// failed start.
struct Runtime {
	Runtime() = default;
	Runtime(const Runtime &) = delete;
	Runtime &operator=(const Runtime &) = delete;
	~Runtime();
};

std::mutex runtime_mutex;
std::weak_ptr<Runtime> current_runtime;

Runtime::~Runtime() {
	std::lock_guard lock(runtime_mutex);
	OpenNI::shutdown();
}

DriverResult<std::shared_ptr<Runtime>> acquire_runtime() {
	using Result = DriverResult<std::shared_ptr<Runtime>>;
	std::lock_guard lock(runtime_mutex);
	if (std::shared_ptr<Runtime> runtime = current_runtime.lock()) {
		return Result::success(std::move(runtime));
	}
	// Note: while it loads drivers, OpenNI changes the process' working directory.
	if (OpenNI::initialize() != openni::STATUS_OK) {
		const std::string reason = extended_error();
		// initialize() counted itself even though it failed; without this, the
		// next call would report success with no drivers loaded.
		OpenNI::shutdown();
		return Result::failure("OpenNI2: cannot initialise: " + reason +
				" (drivers are loaded from <directory of libOpenNI2.so>/OpenNI2/Drivers)");
	}
	auto runtime = std::make_shared<Runtime>();
	current_runtime = runtime;
	return Result::success(std::move(runtime));
}

std::vector<DeviceInfo> enumerate_devices() {
	openni::Array<openni::DeviceInfo> list;
	OpenNI::enumerateDevices(&list);
	std::vector<DeviceInfo> devices;
	for (int i = 0; i < list.getSize(); i++) {
		devices.push_back({ "openni2", list[i].getUri(), list[i].getVendor(), list[i].getName(), "", {} });
	}
	return devices;
}

bool ends_with_oni(const std::string &p_path) {
	if (p_path.size() < 4) {
		return false;
	}
	std::string extension = p_path.substr(p_path.size() - 4);
	std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	return extension == ".oni";
}

// OpenNI answers every bad file with the same "couldn't open device", so the
// file is checked here first. Returns an empty string when it looks playable.
std::string check_recording(const std::string &p_path) {
	std::error_code error;
	const fs::file_status status = fs::status(p_path, error);
	if (!fs::exists(status)) {
		return "file not found";
	}
	if (!fs::is_regular_file(status)) {
		return "not a regular file";
	}
	std::ifstream file(p_path, std::ios::binary);
	char magic[4] = {};
	if (!file.read(magic, sizeof(magic))) {
		return file.is_open() ? "not an .oni recording (shorter than its 4-byte header)" : "cannot be read";
	}
	// Every OpenNI recording starts with the identity "NI10".
	if (std::memcmp(magic, "NI10", 4) != 0) {
		char shown[64];
		std::snprintf(shown, sizeof(shown), "%02x %02x %02x %02x", (unsigned char)magic[0], (unsigned char)magic[1],
				(unsigned char)magic[2], (unsigned char)magic[3]);
		return std::string("not an .oni recording (it starts with bytes ") + shown + ", a recording with \"NI10\")";
	}
	return "";
}

uint64_t host_now_ns() {
	return monotonic_clock_ns(); // never the wall clock, which can jump
}

// The supported mode closest to p_width x p_height at 30 fps in p_format, if any.
const openni::VideoMode *find_mode(const openni::SensorInfo &p_info, openni::PixelFormat p_format, int p_width, int p_height) {
	const openni::Array<openni::VideoMode> &modes = p_info.getSupportedVideoModes();
	const openni::VideoMode *best = nullptr;
	int best_cost = 0;
	for (int i = 0; i < modes.getSize(); i++) {
		const openni::VideoMode &mode = modes[i];
		if (mode.getPixelFormat() != p_format) {
			continue;
		}
		const int cost = std::abs(mode.getResolutionX() - p_width) + std::abs(mode.getResolutionY() - p_height) + std::abs(mode.getFps() - 30);
		if (!best || cost < best_cost) {
			best = &mode;
			best_cost = cost;
		}
	}
	return best;
}

// Reports the device's disconnection; the URI tells it apart from others.
class DisconnectWatch : public OpenNI::DeviceDisconnectedListener {
public:
	explicit DisconnectWatch(std::string p_uri) :
			uri(std::move(p_uri)) {}
	void onDeviceDisconnected(const openni::DeviceInfo *p_info) override {
		if (p_info && uri == p_info->getUri()) {
			disconnected.store(true);
		}
	}

	const std::string uri;
	std::atomic<bool> disconnected{ false };
};

} // namespace

struct OpenNI2Device::State {
	// Declared first, destroyed last: OpenNI must outlive its objects.
	std::shared_ptr<Runtime> runtime;
	std::string name; // "OpenNI2 device 'uri'" or "OpenNI2 recording 'path'", the prefix of every message.
	DeviceInfo info;
	bool file = false;
	bool registered = false;
	openni::Device device;
	std::unique_ptr<openni::VideoStream> depth;
	std::unique_ptr<openni::VideoStream> color;
	std::unique_ptr<DisconnectWatch> watch;
	// Recordings play in OpenNI's manual mode, with repeat on. libOniFile's player thread walks
	// its list of streams without a lock, so a stream destroyed while it runs can crash it (at
	// the end of a recording without repeat it spins through that list). In manual mode it reads
	// a frame only when asked (waitForAnyStream pokes it) and otherwise waits, parked, on its
	// trigger; with repeat it never reaches that end. The end is found here instead, when a
	// stream's frame index starts again, and the recorded pace is kept here: each frame is held
	// until its timestamp, counted from the first one read. No frame is skipped.
	int64_t first_timestamp_us = -1;
	std::chrono::steady_clock::time_point first_read;
	int last_frame_index[2] = { -1, -1 }; // depth, colour
	bool ended = false;

	~State() {
		if (watch) {
			OpenNI::removeDeviceDisconnectedListener(watch.get());
		}
		for (std::unique_ptr<openni::VideoStream> *stream : { &depth, &color }) {
			if (*stream) {
				(*stream)->stop();
				(*stream)->destroy();
			}
		}
		device.close();
	}

	// The next frame of p_stream, or why there is none.
	DriverResult<openni::VideoFrameRef> read(openni::VideoStream *p_stream, const char *p_what, int p_timeout_ms) {
		using Result = DriverResult<openni::VideoFrameRef>;
		if (!p_stream) {
			return Result::failure(name + ": has no " + p_what + " stream");
		}
		if (watch && watch->disconnected.load()) {
			return Result::failure(name + ": disconnected (unplugged?); open it again");
		}
		if (ended) {
			return Result::failure(name + ": end of the recording");
		}
		int ready = -1;
		const openni::Status waited = OpenNI::waitForAnyStream(&p_stream, 1, &ready, std::max(p_timeout_ms, 0));
		if (waited == openni::STATUS_TIME_OUT) {
			return Result::failure(name + ": no " + p_what + " frame within " + std::to_string(p_timeout_ms) + " ms" +
					(file ? " (end of the recording?)" : (watch && watch->disconnected.load()) ? " (disconnected)" : ""));
		}
		openni::VideoFrameRef frame;
		if (waited != openni::STATUS_OK || p_stream->readFrame(&frame) != openni::STATUS_OK || !frame.isValid()) {
			return Result::failure(name + ": cannot read a " + p_what + " frame: " + extended_error());
		}
		if (file) {
			int &last = last_frame_index[p_stream == depth.get() ? 0 : 1];
			if (frame.getFrameIndex() <= last) {
				ended = true; // the player started the recording again
				return Result::failure(name + ": end of the recording");
			}
			last = frame.getFrameIndex();
			keep_recorded_pace(int64_t(frame.getTimestamp()));
		}
		return Result::success(frame);
	}

	// Holds a recording's frame until its time has come, as a live camera would deliver it. A
	// jump forward of more than a second (a gap in the recording) is not waited out.
	void keep_recorded_pace(int64_t p_timestamp_us) {
		using Clock = std::chrono::steady_clock;
		const Clock::time_point now = Clock::now();
		if (first_timestamp_us < 0 || p_timestamp_us < first_timestamp_us) {
			first_timestamp_us = p_timestamp_us;
			first_read = now;
			return;
		}
		const Clock::time_point due = first_read + std::chrono::microseconds(p_timestamp_us - first_timestamp_us);
		if (due - now > std::chrono::seconds(1)) {
			first_timestamp_us = p_timestamp_us;
			first_read = now;
			return;
		}
		if (due > now) {
			std::this_thread::sleep_until(due);
		}
	}
};

DriverResult<std::vector<DeviceInfo>> list_openni2_devices() {
	using Result = DriverResult<std::vector<DeviceInfo>>;
	DriverResult<std::shared_ptr<Runtime>> runtime = acquire_runtime();
	if (!runtime.ok()) {
		return Result::failure(runtime.error);
	}
	return Result::success(enumerate_devices());
}

namespace {

std::string pixel_format_name(openni::PixelFormat p_format) {
	switch (p_format) {
		case openni::PIXEL_FORMAT_DEPTH_1_MM:
			return "1 mm";
		case openni::PIXEL_FORMAT_DEPTH_100_UM:
			return "100 um";
		case openni::PIXEL_FORMAT_SHIFT_9_2:
			return "shift 9.2";
		case openni::PIXEL_FORMAT_SHIFT_9_3:
			return "shift 9.3";
		case openni::PIXEL_FORMAT_RGB888:
			return "RGB888";
		case openni::PIXEL_FORMAT_YUV422:
			return "YUV422";
		case openni::PIXEL_FORMAT_GRAY8:
			return "GRAY8";
		case openni::PIXEL_FORMAT_GRAY16:
			return "GRAY16";
		case openni::PIXEL_FORMAT_JPEG:
			return "JPEG";
		case openni::PIXEL_FORMAT_YUYV:
			return "YUYV";
		default:
			return "format " + std::to_string(int(p_format));
	}
}

} // namespace

DriverResult<std::vector<std::string>> list_openni2_modes(const std::string &p_uri) {
	using Result = DriverResult<std::vector<std::string>>;
	DriverResult<std::unique_ptr<OpenNI2Device>> opened = OpenNI2Device::open(p_uri);
	if (!opened.ok()) {
		return Result::failure(opened.error);
	}
	std::vector<std::string> modes;
	for (const auto &[stream, what] : { std::pair{ opened.value->state->depth.get(), "depth" }, std::pair{ opened.value->state->color.get(), "colour" } }) {
		if (!stream) {
			continue;
		}
		const openni::Array<openni::VideoMode> &supported = stream->getSensorInfo().getSupportedVideoModes();
		for (int i = 0; i < supported.getSize(); i++) {
			const openni::VideoMode &mode = supported[i];
			modes.push_back(std::string(what) + " " + std::to_string(mode.getResolutionX()) + "x" + std::to_string(mode.getResolutionY()) + " " +
					std::to_string(mode.getFps()) + " Hz " + pixel_format_name(mode.getPixelFormat()));
		}
	}
	return Result::success(std::move(modes));
}

DriverResult<OpenNI2Session> OpenNI2Session::start() {
	DriverResult<std::shared_ptr<Runtime>> runtime = acquire_runtime();
	if (!runtime.ok()) {
		return DriverResult<OpenNI2Session>::failure(runtime.error);
	}
	OpenNI2Session session;
	session.runtime = std::move(runtime.value);
	return DriverResult<OpenNI2Session>::success(std::move(session));
}

OpenNI2Device::OpenNI2Device(std::unique_ptr<State> p_state) :
		state(std::move(p_state)) {}

OpenNI2Device::~OpenNI2Device() = default;

DriverResult<std::unique_ptr<OpenNI2Device>> OpenNI2Device::open(const std::string &p_uri) {
	using Result = DriverResult<std::unique_ptr<OpenNI2Device>>;
	std::error_code exists_error;
	const bool file = ends_with_oni(p_uri) || (!p_uri.empty() && fs::exists(p_uri, exists_error));
	const std::string name = std::string(file ? "OpenNI2 recording '" : "OpenNI2 device '") + p_uri + "'";
	if (p_uri.empty()) {
		// OpenNI would open whichever device it finds first.
		return Result::failure(name + ": empty URI (list_openni2_devices() gives the URIs; or pass an .oni path)");
	}
	if (p_uri == "Dummy" || p_uri == "Oz" || p_uri == "PingPong") {
		return Result::failure(name + ": refused: OpenNI2's DummyDevice test driver crashes on open");
	}
	std::string target = p_uri;
	if (file) {
		const std::string problem = check_recording(p_uri);
		if (!problem.empty()) {
			return Result::failure(name + ": " + problem);
		}
		// OpenNI changes the working directory while it loads drivers.
		std::error_code absolute_error;
		const fs::path absolute = fs::absolute(p_uri, absolute_error);
		target = absolute_error ? p_uri : absolute.string();
	}

	DriverResult<std::shared_ptr<Runtime>> runtime = acquire_runtime();
	if (!runtime.ok()) {
		return Result::failure(name + ": " + runtime.error);
	}
	auto state = std::make_unique<State>();
	state->runtime = std::move(runtime.value);
	state->name = name;
	state->file = file;
	openni::Device &device = state->device;
	if (device.open(target.c_str()) != openni::STATUS_OK) {
		if (file) {
			return Result::failure(name + ": OpenNI2 cannot play it: " + extended_error());
		}
		const std::string reason = extended_error();
		const std::vector<DeviceInfo> devices = enumerate_devices();
		const bool listed = std::any_of(devices.begin(), devices.end(), [&](const DeviceInfo &p_info) { return p_info.id == p_uri; });
		if (listed) {
			return Result::failure(name + ": cannot open: " + reason);
		}
		return Result::failure(name + ": not found (" + describe_listed(devices) + ")");
	}

	const openni::DeviceInfo &info = device.getDeviceInfo();
	char serial[ONI_MAX_STR] = {};
	int serial_size = sizeof(serial);
	if (device.getProperty(openni::DEVICE_PROPERTY_SERIAL_NUMBER, serial, &serial_size) != openni::STATUS_OK) {
		serial[0] = '\0';
	}
	serial[sizeof(serial) - 1] = '\0';
	state->info = { "openni2", p_uri, info.getVendor(), info.getName(), serial, {} };

	const struct {
		openni::SensorType type;
		std::unique_ptr<openni::VideoStream> &stream;
		openni::PixelFormat format;
		const char *what;
	} sensors[] = {
		{ openni::SENSOR_DEPTH, state->depth, openni::PIXEL_FORMAT_DEPTH_1_MM, "depth" },
		{ openni::SENSOR_COLOR, state->color, openni::PIXEL_FORMAT_RGB888, "colour" },
	};
	for (const auto &sensor : sensors) {
		if (!device.hasSensor(sensor.type)) {
			continue;
		}
		auto stream = std::make_unique<openni::VideoStream>();
		if (stream->create(device, sensor.type) != openni::STATUS_OK) {
			return Result::failure(name + ": cannot create the " + sensor.what + " stream: " + extended_error());
		}
		// A recording plays as recorded; a live device gets a mode whose depth
		// and colour resolutions match, which registration needs.
		if (!file) {
			if (const openni::VideoMode *mode = find_mode(stream->getSensorInfo(), sensor.format, 640, 480)) {
				stream->setVideoMode(*mode);
			}
		}
		sensor.stream = std::move(stream);
	}
	if (!state->depth && !state->color) {
		return Result::failure(name + ": has neither a depth nor a colour sensor");
	}

	if (file) {
		if (openni::PlaybackControl *playback = device.getPlaybackControl()) {
			// Manual, repeating: see State::first_timestamp_us.
			playback->setRepeatEnabled(true);
			playback->setSpeed(-1.0f);
		}
	} else if (state->depth && state->color) {
		if (device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
			device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR);
		}
		device.setDepthColorSyncEnabled(true);
	}
	state->registered = state->depth && state->color && device.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR;

	for (const auto &sensor : sensors) {
		if (sensor.stream && sensor.stream->start() != openni::STATUS_OK) {
			return Result::failure(name + ": cannot start the " + sensor.what + " stream: " + extended_error());
		}
	}
	if (!file) {
		state->watch = std::make_unique<DisconnectWatch>(p_uri);
		OpenNI::addDeviceDisconnectedListener(state->watch.get());
	}
	return Result::success(std::unique_ptr<OpenNI2Device>(new OpenNI2Device(std::move(state))));
}

DriverResult<DepthFrame> OpenNI2Device::grab_depth(int p_timeout_ms) {
	using Result = DriverResult<DepthFrame>;
	DriverResult<openni::VideoFrameRef> read = state->read(state->depth.get(), "depth", p_timeout_ms);
	if (!read.ok()) {
		return Result::failure(read.error);
	}
	const openni::VideoFrameRef &source = read.value;
	const openni::PixelFormat format = source.getVideoMode().getPixelFormat();
	// 100 um units are divided down, so depth is always in millimetres.
	const int divisor = format == openni::PIXEL_FORMAT_DEPTH_1_MM ? 1 : format == openni::PIXEL_FORMAT_DEPTH_100_UM ? 10 : 0;
	if (divisor == 0) {
		return Result::failure(state->name + ": depth pixel format " + std::to_string(int(format)) + " is not a distance (1 mm or 100 um)");
	}
	const int width = source.getWidth();
	const int height = source.getHeight();
	const int stride = source.getStrideInBytes();
	if (width <= 0 || height <= 0 || stride < width * 2 || source.getDataSize() < stride * (height - 1) + width * 2) {
		return Result::failure(state->name + ": depth frame of " + std::to_string(source.getDataSize()) + " bytes does not hold " +
				std::to_string(width) + "x" + std::to_string(height) + " pixels");
	}
	DepthFrame frame;
	frame.width = width;
	frame.height = height;
	frame.depth_mm.resize(size_t(width) * size_t(height));
	const uint8_t *data = static_cast<const uint8_t *>(source.getData());
	for (int y = 0; y < height; y++) {
		const uint8_t *row = data + size_t(y) * size_t(stride);
		for (int x = 0; x < width; x++) {
			uint16_t value;
			std::memcpy(&value, row + size_t(x) * 2, 2);
			frame.depth_mm[size_t(y) * size_t(width) + size_t(x)] = uint16_t((value + divisor / 2) / divisor);
		}
	}
	frame.registered_to_color = state->registered;
	frame.timestamp_ns = source.getTimestamp() * 1000;
	frame.host_timestamp_ns = host_now_ns();
	frame.frame_index = source.getFrameIndex();
	return Result::success(std::move(frame));
}

DriverResult<ColorFrame> OpenNI2Device::grab_color(int p_timeout_ms) {
	using Result = DriverResult<ColorFrame>;
	DriverResult<openni::VideoFrameRef> read = state->read(state->color.get(), "colour", p_timeout_ms);
	if (!read.ok()) {
		return Result::failure(read.error);
	}
	const openni::VideoFrameRef &source = read.value;
	const openni::PixelFormat format = source.getVideoMode().getPixelFormat();
	const int bytes_per_pixel = format == openni::PIXEL_FORMAT_RGB888 ? 3 : format == openni::PIXEL_FORMAT_GRAY8 ? 1 : 0;
	if (bytes_per_pixel == 0) {
		return Result::failure(state->name + ": colour pixel format " + std::to_string(int(format)) + " is not supported (RGB888 or GRAY8)");
	}
	const int width = source.getWidth();
	const int height = source.getHeight();
	const int stride = source.getStrideInBytes();
	const int row_bytes = width * bytes_per_pixel;
	if (width <= 0 || height <= 0 || stride < row_bytes || source.getDataSize() < stride * (height - 1) + row_bytes) {
		return Result::failure(state->name + ": colour frame of " + std::to_string(source.getDataSize()) + " bytes does not hold " +
				std::to_string(width) + "x" + std::to_string(height) + " pixels");
	}
	ColorFrame frame;
	frame.width = width;
	frame.height = height;
	frame.rgb.resize(size_t(width) * size_t(height) * 3);
	const uint8_t *data = static_cast<const uint8_t *>(source.getData());
	for (int y = 0; y < height; y++) {
		const uint8_t *row = data + size_t(y) * size_t(stride);
		uint8_t *out = frame.rgb.data() + size_t(y) * size_t(width) * 3;
		if (bytes_per_pixel == 3) {
			std::memcpy(out, row, size_t(row_bytes));
		} else {
			for (int x = 0; x < width; x++) {
				out[x * 3] = out[x * 3 + 1] = out[x * 3 + 2] = row[x];
			}
		}
	}
	frame.timestamp_ns = source.getTimestamp() * 1000;
	frame.host_timestamp_ns = host_now_ns();
	frame.frame_index = source.getFrameIndex();
	return Result::success(std::move(frame));
}

DriverResult<RgbdGrab> OpenNI2Device::grab(int p_timeout_ms) {
	using Result = DriverResult<RgbdGrab>;
	using Clock = std::chrono::steady_clock;
	const Clock::time_point start = Clock::now();
	DriverResult<DepthFrame> depth = grab_depth(p_timeout_ms);
	if (!depth.ok()) {
		return Result::failure(depth.error);
	}
	const int spent_ms = int(std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count());
	DriverResult<ColorFrame> color = grab_color(std::max(p_timeout_ms - spent_ms, 0));
	if (!color.ok()) {
		return Result::failure(color.error);
	}
	return Result::success({ std::move(depth.value), std::move(color.value) });
}

DeviceInfo OpenNI2Device::get_info() const {
	return state->info;
}

bool OpenNI2Device::is_file() const {
	return state->file;
}

bool OpenNI2Device::has_depth() const {
	return state->depth != nullptr;
}

bool OpenNI2Device::has_color() const {
	return state->color != nullptr;
}

bool OpenNI2Device::is_depth_registered() const {
	return state->registered;
}

bool OpenNI2Device::is_disconnected() const {
	return state->watch && state->watch->disconnected.load();
}

} // namespace roomprobe::drivers
