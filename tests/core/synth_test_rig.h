#pragma once
// The rig the synthetic-rig tests render with (test_synth_renderer.cpp, test_synth_sequence.cpp).

#include "rig/rig.h"

#include <glm/gtc/quaternion.hpp>

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
