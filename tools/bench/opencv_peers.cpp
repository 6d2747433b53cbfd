#include "opencv_peers.h"

#include <opencv2/rgbd.hpp>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <chrono>
#include <exception>

namespace roomprobe::bench {

namespace {

double ms_since(std::chrono::steady_clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - p_start).count();
}

cv::Matx44f matrix_of(const Pose &p_pose) {
	const glm::dmat3 r = glm::mat3_cast(p_pose.rotation);
	cv::Matx44f m = cv::Matx44f::eye();
	for (int row = 0; row < 3; row++) {
		for (int col = 0; col < 3; col++) {
			m(row, col) = float(r[col][row]); // glm is column-major
		}
		m(row, 3) = float(p_pose.translation[row]);
	}
	return m;
}

// The readings the peer may use: RoomProbe's depth range, 0 elsewhere (kinfu's "no reading").
cv::Mat peer_depth(const cv::Mat &p_depth_m, float p_min_m, float p_max_m) {
	cv::Mat depth(p_depth_m.size(), CV_32FC1);
	for (int y = 0; y < depth.rows; y++) {
		const float *in = p_depth_m.ptr<float>(y);
		float *out = depth.ptr<float>(y);
		for (int x = 0; x < depth.cols; x++) {
			out[x] = in[x] >= p_min_m && in[x] <= p_max_m ? in[x] : 0.0f; // NaN fails both
		}
	}
	return depth;
}

} // namespace

PeerTimings run_opencv_peers(const std::vector<PeerFrame> &p_frames, const PeerSettings &p_settings) {
	PeerTimings timings;
	std::vector<cv::Mat> depths;
	depths.reserve(p_frames.size());
	for (const PeerFrame &frame : p_frames) {
		depths.push_back(peer_depth(frame.depth_m, p_settings.min_depth_m, p_settings.max_depth_m));
	}
	const PinholeIntrinsics &c = p_settings.camera;
	try {
		const cv::Ptr<cv::kinfu::VolumeParams> defaults = cv::kinfu::VolumeParams::defaultParams(cv::kinfu::VolumeType::HASHTSDF);
		const int unit = defaults->unitResolution > 0 ? defaults->unitResolution : 16;
		const cv::Ptr<cv::kinfu::Volume> volume = cv::kinfu::makeVolume(cv::kinfu::VolumeType::HASHTSDF, p_settings.voxel_size_m, cv::Matx44f::eye(),
				defaults->raycastStepFactor, p_settings.truncation_m, p_settings.max_weight, p_settings.max_depth_m, cv::Vec3i(unit, unit, unit));
		timings.volume = "HASHTSDF";
		const cv::kinfu::Intr intrinsics(c.fx, c.fy, c.cx, c.cy);
		const PinholeIntrinsics reference = c.level(p_settings.raycast_level);
		const cv::kinfu::Intr reference_intrinsics(reference.fx, reference.fy, reference.cx, reference.cy);
		timings.raycast_width = reference.width;
		timings.raycast_height = reference.height;
		for (size_t i = 0; i < p_frames.size(); i++) {
			const cv::Matx44f pose = matrix_of(p_frames[i].world_from_camera);
			auto start = std::chrono::steady_clock::now();
			volume->integrate(depths[i], 1.0f, pose, intrinsics, int(i));
			timings.integrate_ms.push_back(ms_since(start));
			cv::Mat points, normals;
			start = std::chrono::steady_clock::now();
			volume->raycast(pose, reference_intrinsics, cv::Size(reference.width, reference.height), points, normals);
			timings.raycast_ms.push_back(ms_since(start));
		}
	} catch (const std::exception &e) {
		timings.error = std::string("cv::kinfu HASHTSDF: ") + e.what();
	}
	try {
		const cv::Mat camera_matrix = (cv::Mat_<float>(3, 3) << c.fx, 0.0f, c.cx, 0.0f, c.fy, c.cy, 0.0f, 0.0f, 1.0f);
		cv::rgbd::ICPOdometry odometry(camera_matrix);
		odometry.setMinDepth(p_settings.min_depth_m);
		odometry.setMaxDepth(p_settings.max_depth_m);
		const cv::Mat no_mask, no_image;
		for (size_t i = 1; i < depths.size(); i++) {
			cv::Mat rt;
			const auto start = std::chrono::steady_clock::now();
			odometry.compute(no_image, depths[i], no_mask, no_image, depths[i - 1], no_mask, rt);
			timings.icp_ms.push_back(ms_since(start));
		}
	} catch (const std::exception &e) {
		timings.error += (timings.error.empty() ? "" : "; ") + std::string("cv::rgbd::ICPOdometry: ") + e.what();
	}
	return timings;
}

} // namespace roomprobe::bench
