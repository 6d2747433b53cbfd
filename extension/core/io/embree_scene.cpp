#include "embree_scene.h"

#if __has_include(<embree4/rtcore.h>)
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <algorithm>

namespace roomprobe {

namespace {

RTCDevice as_device(void *p) { return static_cast<RTCDevice>(p); }
RTCScene as_scene(void *p) { return static_cast<RTCScene>(p); }

// Embree 4 dropped the intersect context argument (its optional arguments come last instead).
void intersect1(RTCScene p_scene, RTCRayHit *r_ray_hit) {
#if RTC_VERSION_MAJOR >= 4
	rtcIntersect1(p_scene, r_ray_hit, nullptr);
#else
	RTCIntersectContext context;
	rtcInitIntersectContext(&context);
	rtcIntersect1(p_scene, &context, r_ray_hit);
#endif
}

std::string error_name(RTCError p_error) {
#if RTC_VERSION_MAJOR >= 4
	return rtcGetErrorString(p_error);
#else
	return "error " + std::to_string(static_cast<int>(p_error));
#endif
}

void occluded1(RTCScene p_scene, RTCRay *r_ray) {
#if RTC_VERSION_MAJOR >= 4
	rtcOccluded1(p_scene, r_ray, nullptr);
#else
	RTCIntersectContext context;
	rtcInitIntersectContext(&context);
	rtcOccluded1(p_scene, &context, r_ray);
#endif
}

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
		rtcReleaseScene(as_scene(scene));
	}
	if (device) {
		rtcReleaseDevice(as_device(device));
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
		rtcReleaseScene(as_scene(scene));
	}
	RTCScene new_scene = rtcNewScene(as_device(device));
	scene = new_scene;
	if (p_high_quality) {
		rtcSetSceneBuildQuality(new_scene, RTC_BUILD_QUALITY_HIGH);
	}
	RTCGeometry geometry = rtcNewGeometry(as_device(device), RTC_GEOMETRY_TYPE_TRIANGLE);
	float *vb = static_cast<float *>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), p_xyz.size() / 3));
	uint32_t *ib = static_cast<uint32_t *>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), p_indices.size() / 3));
	if (!vb || !ib) {
		rtcReleaseGeometry(geometry);
		rtcReleaseScene(new_scene);
		scene = nullptr;
		return "Embree: cannot allocate the geometry buffers";
	}
	std::copy(p_xyz.begin(), p_xyz.end(), vb);
	std::copy(p_indices.begin(), p_indices.end(), ib);
	rtcCommitGeometry(geometry);
	rtcAttachGeometry(new_scene, geometry);
	rtcReleaseGeometry(geometry);
	rtcCommitScene(new_scene);
	const RTCError status = rtcGetDeviceError(as_device(device));
	if (status != RTC_ERROR_NONE) {
		return "Embree: " + error_name(status);
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
	intersect1(as_scene(scene), &rh);
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
	occluded1(as_scene(scene), &ray);
	return ray.tfar < 0.0f; // Embree sets tfar to -inf on a hit
}

} // namespace roomprobe
