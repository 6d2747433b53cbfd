#include "embree_scene.h"

#include <algorithm>

namespace roomprobe {

namespace {

// One ray for Embree's queries: origin + t * direction, t in (t_near, t_far), every mask bit.
RTCRay make_ray(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) {
	RTCRay ray;
	ray.org_x = static_cast<float>(p_origin.x);
	ray.org_y = static_cast<float>(p_origin.y);
	ray.org_z = static_cast<float>(p_origin.z);
	ray.dir_x = static_cast<float>(p_direction.x);
	ray.dir_y = static_cast<float>(p_direction.y);
	ray.dir_z = static_cast<float>(p_direction.z);
	ray.tnear = static_cast<float>(p_t_near);
	ray.tfar = static_cast<float>(std::min(p_t_far, 1e30));
	ray.time = 0.0f;
	ray.mask = 0xffffffffu;
	ray.id = 0;
	ray.flags = 0;
	return ray;
}

} // namespace

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

bool EmbreeTriangleScene::intersect(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far, RayHit *r_hit) const {
	if (!scene) {
		return false;
	}
	RTCRayHit rh;
	rh.ray = make_ray(p_origin, p_direction, p_t_near, p_t_far);
	rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
	rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
	rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
	rtcIntersect1(scene, &rh, nullptr);
	if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
		return false;
	}
	r_hit->t = rh.ray.tfar;
	r_hit->triangle = rh.hit.primID;
	r_hit->geometric_normal = glm::vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
	r_hit->u = rh.hit.u;
	r_hit->v = rh.hit.v;
	return true;
}

bool EmbreeTriangleScene::occluded(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) const {
	if (!scene) {
		return false;
	}
	RTCRay ray = make_ray(p_origin, p_direction, p_t_near, p_t_far);
	rtcOccluded1(scene, &ray, nullptr);
	return ray.tfar < 0.0f; // Embree sets tfar to -inf on a hit
}

} // namespace roomprobe
