#include "uvc/v4l2_devices.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

namespace roomprobe::drivers {

namespace {

// Closes the node however listing leaves.
class NodeHandle {
public:
	explicit NodeHandle(const std::string &p_path) :
			fd(::open(p_path.c_str(), O_RDWR | O_NONBLOCK)) {}
	~NodeHandle() {
		if (fd >= 0) {
			::close(fd);
		}
	}
	NodeHandle(const NodeHandle &) = delete;
	NodeHandle &operator=(const NodeHandle &) = delete;
	const int fd;
};

std::string fourcc_text(uint32_t p_fourcc) {
	std::string text;
	for (int i = 0; i < 4; i++) {
		const char c = char((p_fourcc >> (8 * i)) & 0xff);
		if (c != ' ') {
			text += c;
		}
	}
	return text;
}

std::vector<std::string> list_modes(int p_fd) {
	std::vector<std::string> modes;
	v4l2_fmtdesc format{};
	format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	for (format.index = 0; ioctl(p_fd, VIDIOC_ENUM_FMT, &format) == 0; format.index++) {
		v4l2_frmsizeenum size{};
		size.pixel_format = format.pixelformat;
		for (size.index = 0; ioctl(p_fd, VIDIOC_ENUM_FRAMESIZES, &size) == 0; size.index++) {
			if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
				modes.push_back(fourcc_text(format.pixelformat) + " " + std::to_string(size.discrete.width) + "x" + std::to_string(size.discrete.height));
			} else {
				modes.push_back(fourcc_text(format.pixelformat) + " " + std::to_string(size.stepwise.min_width) + "x" + std::to_string(size.stepwise.min_height) +
						" to " + std::to_string(size.stepwise.max_width) + "x" + std::to_string(size.stepwise.max_height));
				break;
			}
		}
	}
	return modes;
}

} // namespace

std::vector<DeviceInfo> list_v4l2_devices() {
	std::vector<std::string> nodes;
	std::error_code error;
	for (const auto &entry : std::filesystem::directory_iterator("/dev", error)) {
		const std::string name = entry.path().filename().string();
		if (name.rfind("video", 0) == 0) {
			nodes.push_back(entry.path().string());
		}
	}
	std::sort(nodes.begin(), nodes.end());
	std::vector<DeviceInfo> devices;
	for (const std::string &node : nodes) {
		NodeHandle handle(node);
		v4l2_capability capability{};
		if (handle.fd < 0 || ioctl(handle.fd, VIDIOC_QUERYCAP, &capability) != 0) {
			continue;
		}
		const uint32_t caps = (capability.capabilities & V4L2_CAP_DEVICE_CAPS) ? capability.device_caps : capability.capabilities;
		if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
			continue; // a metadata or output node of the same camera
		}
		DeviceInfo info;
		info.backend = "v4l2";
		info.id = node;
		info.vendor = reinterpret_cast<const char *>(capability.driver);
		info.model = reinterpret_cast<const char *>(capability.card);
		info.serial = reinterpret_cast<const char *>(capability.bus_info);
		info.modes = list_modes(handle.fd);
		devices.push_back(std::move(info));
	}
	return devices;
}

} // namespace roomprobe::drivers
