// slam/dense_slam.h on real frames: 400 consecutive frames of a Kinect v1 (Microsoft 7-Scenes,
// ../shared/data/rgbd-7scenes, see its README) tracked frame to model against the dataset's
// reference poses.

#include <io/opencv.h>

#include "slam/dense_slam.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

const std::string k_dir = std::string(ROOMPROBE_SHARED_DATA) + "/rgbd-7scenes";

bool load_pose(const std::string &p_path, Pose *r_pose) {
	std::ifstream in(p_path);
	glm::dmat4 m(1.0);
	for (int r = 0; r < 4; r++) {
		for (int c = 0; c < 4; c++) {
			if (!(in >> m[c][r])) {
				return false;
			}
		}
	}
	*r_pose = pose_from_matrix(m);
	return true;
}

double env_or(const char *p_name, double p_default) {
	const char *v = std::getenv(p_name);
	return v != nullptr ? std::atof(v) : p_default;
}

} // namespace

TEST_CASE("dense SLAM: 400 real Kinect frames (7-Scenes) track with no frame lost") {
	PinholeParams camera;
	camera.width = 640;
	camera.height = 480;
	camera.fx = camera.fy = 585.0;
	camera.cx = 320.0;
	camera.cy = 240.0;
	const int frames = int(env_or("RP_FRAMES", 400));
	DenseSlamOptions options;
	options.icp.colour_weight = env_or("RP_CW", options.icp.colour_weight);
	options.icp.max_depth_m = env_or("RP_ICP_MAX", options.icp.max_depth_m);
	options.tsdf.max_depth_m = float(env_or("RP_TSDF_MAX", options.tsdf.max_depth_m));
	options.tsdf.voxel_size_m = float(env_or("RP_VOXEL", options.tsdf.voxel_size_m));
	options.tsdf.truncation_m = float(env_or("RP_TRUNC", options.tsdf.truncation_m));
	options.raycast_level = int(env_or("RP_RAYLEVEL", options.raycast_level));
	options.icp.max_distance_m = env_or("RP_MAXDIST", options.icp.max_distance_m);
	options.icp.levels = int(env_or("RP_LEVELS", options.icp.levels));
	options.icp.min_constraint = env_or("RP_MINC", options.icp.min_constraint);
	options.icp.depth_noise.b_per_m2 = env_or("RP_NOISEB", options.icp.depth_noise.b_per_m2);
	options.icp.depth_noise.reference_m = env_or("RP_NOISEREF", options.icp.depth_noise.reference_m);
	options.icp.colour_always = env_or("RP_CALWAYS", 0) != 0;
	options.icp.iterations[0] = int(env_or("RP_IT0", options.icp.iterations[0]));
	options.icp.iterations[1] = int(env_or("RP_IT1", options.icp.iterations[1]));
	options.icp.max_normal_angle_deg = env_or("RP_NANG", options.icp.max_normal_angle_deg);
	options.icp.surface.smoothing_radius_px = int(env_or("RP_SMOOTH", options.icp.surface.smoothing_radius_px));
	DenseSlam slam(options);
	Pose first;
	REQUIRE(load_pose(k_dir + "/frame-000000.pose.txt", &first));
	REQUIRE(slam.configure(camera, first) == "");
	double sum_sq = 0.0, max_m = 0.0, track_ms = 0.0;
	int good = 0, poor = 0, lost = 0;
	for (int i = 0; i < frames; i++) {
		char name[64];
		std::snprintf(name, sizeof(name), "/frame-%06d", i);
		const std::string base = k_dir + name;
		cv::Mat depth16 = cv::imread(base + ".depth.png", cv::IMREAD_UNCHANGED);
		cv::Mat bgr = cv::imread(base + ".color.jpg", cv::IMREAD_COLOR);
		REQUIRE(!depth16.empty());
		RgbdFrame frame;
		frame.timestamp_s = i / 30.0;
		depth16.convertTo(frame.depth_m, CV_32FC1, 0.001);
		frame.depth_m.setTo(std::numeric_limits<float>::quiet_NaN(), depth16 == 0);
		cv::cvtColor(bgr, frame.rgb, cv::COLOR_BGR2RGB);
		const DenseSlamFrame out = slam.process(frame);
		track_ms += out.timings.track_ms;
		Pose truth;
		REQUIRE(load_pose(base + ".pose.txt", &truth));
		good += out.tracking.state == TrackingState::Good;
		poor += out.tracking.state == TrackingState::Poor;
		lost += out.tracking.state == TrackingState::Lost;
		if (std::getenv("RP_VERBOSE") != nullptr) {
			std::printf("frame %d %s c=%.4f col=%d: %s\n", i, tracking_state_name(out.tracking.state), out.tracking.constraint, int(out.tracking.colour_used), out.tracking.reason.c_str());
		}
		if (std::getenv("RP_DUMP") != nullptr) {
			static FILE *f = std::fopen(std::getenv("RP_DUMP"), "w");
			const Pose &p = slam.pose();
			std::fprintf(f, "%d %f %f %f %f %f %f %f %f %f %f %f %f %f %f\n", i, p.translation.x, p.translation.y, p.translation.z, p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z,
					truth.translation.x, truth.translation.y, truth.translation.z, truth.rotation.w, truth.rotation.x, truth.rotation.y, truth.rotation.z);
			std::fflush(f);
		}
		const double e = translation_difference_m(slam.pose(), truth);
		sum_sq += e * e;
		max_m = std::max(max_m, e);
	}
	const double ate_m = std::sqrt(sum_sq / frames);
	std::printf("7-Scenes: ATE %.1f mm max %.1f mm, good %d poor %d lost %d, track %.1f ms/frame\n", ate_m * 1000.0, max_m * 1000.0, good, poor,
			lost, track_ms / frames);
	CHECK(lost == 0);
}
