#pragma once
// Analytic ground truth for the dense SLAM tests (test_slam_tsdf.cpp, test_slam_meshing.cpp):
// spheres and axis-aligned boxes intersected exactly, rendered to z depth and a smooth colour
// pattern by one camera at a known pose.

#include <io/opencv.h>

#include "camera/pinhole_camera.h"
#include "math/pose.h"
#include "synth_test_rig.h"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <cmath>
#include <limits>
#include <vector>

namespace slam_test {

// The 640 x 480, fx = fy = 525 RGB-D camera of the synthetic rig, optionally at 1 / 2^level size.
inline roomprobe::PinholeIntrinsics rig_camera(int p_level = 0) {
	const roomprobe::PinholeParams &p = test_rig().rgb;
	const roomprobe::PinholeIntrinsics full { float(p.fx), float(p.fy), float(p.cx), float(p.cy), p.width, p.height };
	return full.level(p_level);
}

// The pose of a camera at p_eye looking at p_target (OpenCV axes: x right, y down, z forward),
// with world +Y up.
inline roomprobe::Pose look_at(const glm::dvec3 &p_eye, const glm::dvec3 &p_target) {
	const glm::dvec3 z = glm::normalize(p_target - p_eye);
	const glm::dvec3 x = glm::normalize(glm::cross(z, glm::dvec3(0.0, 1.0, 0.0)));
	const glm::dvec3 y = glm::cross(z, x);
	roomprobe::Pose pose;
	pose.rotation = glm::quat_cast(glm::dmat3(x, y, z));
	pose.translation = p_eye;
	return pose;
}

// A camera on a sphere around p_target: azimuth about +Y from +Z, elevation above the horizon.
inline roomprobe::Pose orbit_pose(const glm::dvec3 &p_target, double p_distance, double p_azimuth_deg, double p_elevation_deg) {
	const double a = glm::radians(p_azimuth_deg), e = glm::radians(p_elevation_deg);
	const glm::dvec3 eye = p_target + p_distance * glm::dvec3(std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a));
	return look_at(eye, p_target);
}

// A smooth colour at every world point (R, G, B, 28..228): at most 800 levels per metre.
inline glm::dvec3 pattern_color(const glm::dvec3 &p_world) {
	return { 128.0 + 100.0 * std::sin(8.0 * p_world.x), 128.0 + 100.0 * std::sin(8.0 * p_world.y + 1.0), 128.0 + 100.0 * std::sin(8.0 * p_world.z + 2.0) };
}
constexpr double PATTERN_MAX_GRADIENT = 800.0; // levels per metre, per channel

struct Scene {
	struct Sphere {
		glm::dvec3 centre;
		double radius;
	};
	struct Box {
		glm::dvec3 lo, hi;
	};
	std::vector<Sphere> spheres;
	std::vector<Box> boxes;

	// The nearest hit of a ray (unit p_dir) at t > 0: distance, outward normal and a surface id
	// (one per sphere, one per box face) to find edges between surfaces.
	bool intersect(const glm::dvec3 &p_origin, const glm::dvec3 &p_dir, double *r_t, glm::dvec3 *r_normal, int *r_id) const {
		double best = std::numeric_limits<double>::infinity();
		for (size_t i = 0; i < spheres.size(); i++) {
			const glm::dvec3 oc = p_origin - spheres[i].centre;
			const double b = glm::dot(oc, p_dir);
			const double c = glm::dot(oc, oc) - spheres[i].radius * spheres[i].radius;
			const double disc = b * b - c;
			if (disc < 0.0) {
				continue;
			}
			const double t = -b - std::sqrt(disc);
			if (t > 1e-9 && t < best) {
				best = t;
				*r_normal = glm::normalize(oc + t * p_dir);
				*r_id = int(i);
			}
		}
		for (size_t i = 0; i < boxes.size(); i++) {
			double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
			int axis = -1;
			double sign = 0.0;
			for (int a = 0; a < 3; a++) {
				const double inv = 1.0 / p_dir[a];
				double ta = (boxes[i].lo[a] - p_origin[a]) * inv, tb = (boxes[i].hi[a] - p_origin[a]) * inv;
				double s = -1.0; // entering through lo: the face's normal is -axis
				if (ta > tb) {
					std::swap(ta, tb);
					s = 1.0;
				}
				if (ta > t0) {
					t0 = ta;
					axis = a;
					sign = s;
				}
				t1 = std::min(t1, tb);
			}
			if (axis >= 0 && t0 <= t1 && t0 > 1e-9 && t0 < best) {
				best = t0;
				*r_normal = glm::dvec3(0.0);
				(*r_normal)[axis] = sign;
				*r_id = 100 + int(i) * 6 + axis * 2 + (sign > 0.0);
			}
		}
		if (!std::isfinite(best)) {
			return false;
		}
		*r_t = best;
		return true;
	}
};

// One rendered frame: what the sensor gives plus the ground truth per pixel.
struct Frame {
	cv::Mat depth; // CV_32FC1, z metres, NaN where no hit
	cv::Mat rgb; // CV_8UC3, R, G, B
	cv::Mat normals; // CV_32FC3, world, unit, outward
	cv::Mat ids; // CV_32SC1, surface id, -1 where no hit
	cv::Mat incidence_deg; // CV_32FC1, angle between the normal and the direction to the camera
	roomprobe::Pose world_from_camera;
};

inline Frame render(const Scene &p_scene, const roomprobe::PinholeIntrinsics &p_camera, const roomprobe::Pose &p_world_from_camera) {
	const float nan = std::numeric_limits<float>::quiet_NaN();
	Frame f;
	f.world_from_camera = p_world_from_camera;
	f.depth = cv::Mat(p_camera.height, p_camera.width, CV_32FC1, cv::Scalar(nan));
	f.rgb = cv::Mat(p_camera.height, p_camera.width, CV_8UC3, cv::Scalar::all(0));
	f.normals = cv::Mat(p_camera.height, p_camera.width, CV_32FC3, cv::Scalar::all(nan));
	f.ids = cv::Mat(p_camera.height, p_camera.width, CV_32SC1, cv::Scalar(-1));
	f.incidence_deg = cv::Mat(p_camera.height, p_camera.width, CV_32FC1, cv::Scalar(nan));
	const glm::dmat3 rotation = glm::mat3_cast(p_world_from_camera.rotation);
	for (int v = 0; v < p_camera.height; v++) {
		for (int u = 0; u < p_camera.width; u++) {
			const glm::dvec3 ray_camera(p_camera.unproject(glm::vec2(float(u), float(v)), 1.0f));
			const glm::dvec3 dir = glm::normalize(rotation * ray_camera);
			double t;
			glm::dvec3 n;
			int id;
			if (!p_scene.intersect(p_world_from_camera.translation, dir, &t, &n, &id)) {
				continue;
			}
			const glm::dvec3 hit = p_world_from_camera.translation + t * dir;
			const glm::dvec3 c = pattern_color(hit);
			f.depth.at<float>(v, u) = float(t / glm::length(ray_camera)); // z of the hit
			f.rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(uint8_t(std::lround(c.x)), uint8_t(std::lround(c.y)), uint8_t(std::lround(c.z)));
			f.normals.at<cv::Vec3f>(v, u) = cv::Vec3f(float(n.x), float(n.y), float(n.z));
			f.ids.at<int>(v, u) = id;
			f.incidence_deg.at<float>(v, u) = float(glm::degrees(std::acos(std::clamp(-glm::dot(n, dir), -1.0, 1.0))));
		}
	}
	return f;
}

// Pixels within p_radius pixels of another surface or of no surface: where depth jumps.
inline cv::Mat edge_mask(const Frame &p_frame, int p_radius) {
	cv::Mat edges(p_frame.ids.size(), CV_8UC1, cv::Scalar(0));
	for (int v = 0; v < edges.rows; v++) {
		for (int u = 0; u < edges.cols; u++) {
			const int id = p_frame.ids.at<int>(v, u);
			for (int dv = -p_radius; dv <= p_radius && !edges.at<uint8_t>(v, u); dv++) {
				for (int du = -p_radius; du <= p_radius; du++) {
					const int y = std::clamp(v + dv, 0, edges.rows - 1), x = std::clamp(u + du, 0, edges.cols - 1);
					if (p_frame.ids.at<int>(y, x) != id) {
						edges.at<uint8_t>(v, u) = 1;
						break;
					}
				}
			}
		}
	}
	return edges;
}

} // namespace slam_test
