#pragma once
// The rig the synthetic-rig tests render with (test_synth_renderer.cpp, test_synth_sequence.cpp).

#include "rig/rig.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

// The synthetic rig of calib/synthetic_rig.yaml, spelt out so that the tests do not depend on the
// working directory.
inline roomprobe::Rig test_rig() {
	roomprobe::Rig rig;
	rig.rgb.width = 640;
	rig.rgb.height = 480;
	rig.rgb.fx = rig.rgb.fy = 525.0;
	rig.rgb.cx = 319.5;
	rig.rgb.cy = 239.5;
	rig.depth_scale_m = 0.001;
	roomprobe::OmniParams &f = rig.fisheye;
	f.width = f.height = 1024;
	f.xi = 1.0;
	f.fx = f.fy = 478.645871127404;
	f.cx = f.cy = 511.5;
	f.circle_cx = f.circle_cy = 511.5;
	f.circle_radius = 500.0;
	f.max_angle_deg = 92.5;
	rig.rgb_from_fisheye.rotation = glm::dquat(std::sqrt(0.5), std::sqrt(0.5), 0.0, 0.0); // (w, x, y, z)
	rig.rgb_from_fisheye.translation = glm::dvec3(0.0, -0.08, 0.02);
	rig.fisheye_time_offset_s = 0.0137;
	return rig;
}

// The test rig's fisheye at 1 / p_divisor of its size (1024 / p_divisor pixels square, the same
// field of view), for faster renders.
inline roomprobe::OmniParams scaled_test_fisheye(int p_divisor) {
	roomprobe::OmniParams f = test_rig().fisheye;
	f.width = f.height = f.width / p_divisor;
	f.fx = f.fy = f.fx / p_divisor;
	f.cx = f.cy = f.circle_cx = f.circle_cy = (f.width - 1) * 0.5;
	f.circle_radius /= p_divisor;
	return f;
}

// test_rig() shrunk for live and recording tests: a p_rgb_width x p_rgb_height RGB camera (focal
// 50 px) and a p_fisheye_width x p_fisheye_height fisheye whose image circle fills 90 % of it,
// both on one clock (fisheye_time_offset_s 0, as a live rig is).
inline roomprobe::Rig small_test_rig(int p_rgb_width, int p_rgb_height, int p_fisheye_width, int p_fisheye_height) {
	roomprobe::Rig rig = test_rig();
	rig.rgb.width = p_rgb_width;
	rig.rgb.height = p_rgb_height;
	rig.rgb.fx = rig.rgb.fy = 50.0;
	rig.rgb.cx = (p_rgb_width - 1) * 0.5;
	rig.rgb.cy = (p_rgb_height - 1) * 0.5;
	rig.fisheye.width = p_fisheye_width;
	rig.fisheye.height = p_fisheye_height;
	rig.fisheye.cx = rig.fisheye.circle_cx = (p_fisheye_width - 1) * 0.5;
	rig.fisheye.cy = rig.fisheye.circle_cy = (p_fisheye_height - 1) * 0.5;
	rig.fisheye.circle_radius = std::min(p_fisheye_width, p_fisheye_height) * 0.45;
	rig.fisheye.fx = rig.fisheye.fy = rig.fisheye.circle_radius;
	rig.fisheye_time_offset_s = 0.0;
	return rig;
}
