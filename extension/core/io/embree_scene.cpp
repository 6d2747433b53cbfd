#include "embree_scene.h"

#include <algorithm>

namespace roomprobe {

EmbreeTriangleScene::~EmbreeTriangleScene() {
	if (scene) {
		rtcReleaseScene(scene);
	}
	if (device) {
		rtcReleaseDevice(device);
	}
}

std::string EmbreeTriangleScene::build(const std::vector<float> &p_xyz, const std::vector<uint32_t> &p_indices, bool p_high_quality) {
	if (!device) {
		device = rtcNewDevice(nullptr);
		if (!device) {
			return "Embree: cannot create a device (error " + std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")";
		}
	}
	if (scene) {
		rtcReleaseScene(scene);
	}
	scene = rtcNewScene(device);
	if (p_high_quality) {
		rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
	}
	RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
	float *vb = static_cast<float *>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), p_xyz.size() / 3));
	uint32_t *ib = static_cast<uint32_t *>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), p_indices.size() / 3));
	if (!vb || !ib) {
		rtcReleaseGeometry(geometry);
		rtcReleaseScene(scene);
		scene = nullptr;
		return "Embree: cannot allocate the geometry buffers";
	}
	std::copy(p_xyz.begin(), p_xyz.end(), vb);
	std::copy(p_indices.begin(), p_indices.end(), ib);
	rtcCommitGeometry(geometry);
	rtcAttachGeometry(scene, geometry);
	rtcReleaseGeometry(geometry);
	rtcCommitScene(scene);
	const RTCError status = rtcGetDeviceError(device);
	if (status != RTC_ERROR_NONE) {
		return std::string("Embree: ") + rtcGetErrorString(status);
	}
	return "";
}

} // namespace roomprobe
