#include "keyframes.h"

#include "depth_pyramid.h"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace roomprobe {

namespace {

// The camera's optical axis in the world.
glm::dvec3 view_direction(const Pose &p_pose) {
	return glm::normalize(p_pose.rotation * glm::dvec3(0.0, 0.0, 1.0));
}

} // namespace

KeyframeThumbnail KeyframeDatabase::thumbnail(const cv::Mat &p_depth_m, const cv::Mat &p_rgb) const {
	const int w = std::max(1, opts.thumbnail_width), h = std::max(1, opts.thumbnail_height);
	KeyframeThumbnail out;
	out.depth_m = cv::Mat::zeros(h, w, CV_32FC1);
	out.intensity = cv::Mat::zeros(h, w, CV_32FC1);
	const cv::Mat grey = p_rgb.empty() ? cv::Mat() : intensity_of(p_rgb);
	cv::Mat count = cv::Mat::zeros(h, w, CV_32FC1);
	for (int v = 0; v < p_depth_m.rows; v++) {
		const float *depth = p_depth_m.ptr<float>(v);
		const float *intensity = grey.empty() ? nullptr : grey.ptr<float>(v);
		const int r = v * h / p_depth_m.rows;
		for (int u = 0; u < p_depth_m.cols; u++) {
			if (!(depth[u] > 0.0f)) {
				continue; // NaN or none
			}
			const int c = u * w / p_depth_m.cols;
			out.depth_m.at<float>(r, c) += depth[u];
			out.intensity.at<float>(r, c) += intensity != nullptr ? intensity[u] : 0.0f;
			count.at<float>(r, c) += 1.0f;
		}
	}
	// Block means; a block with under a quarter of its pixels read counts as none.
	const float quarter = 0.25f * float(p_depth_m.rows / h) * float(p_depth_m.cols / w);
	double sum = 0.0, sum_sq = 0.0;
	int blocks = 0;
	for (int r = 0; r < h; r++) {
		for (int c = 0; c < w; c++) {
			const float n = count.at<float>(r, c);
			if (n < std::max(1.0f, quarter)) {
				out.depth_m.at<float>(r, c) = 0.0f;
				out.intensity.at<float>(r, c) = 0.0f;
				continue;
			}
			out.depth_m.at<float>(r, c) /= n;
			const float i = out.intensity.at<float>(r, c) /= n;
			sum += i;
			sum_sq += double(i) * i;
			blocks++;
		}
	}
	out.usable = blocks >= int(opts.min_overlap * w * h);
	if (blocks == 0) {
		return out;
	}
	const double mean = sum / blocks;
	const double deviation = std::sqrt(std::max(0.0, sum_sq / blocks - mean * mean));
	for (int r = 0; r < h; r++) {
		for (int c = 0; c < w; c++) {
			if (out.depth_m.at<float>(r, c) > 0.0f) {
				float &i = out.intensity.at<float>(r, c);
				i = deviation > 1e-6 ? float((i - mean) / deviation) : 0.0f;
			}
		}
	}
	return out;
}

bool KeyframeDatabase::wants(const Pose &p_world_from_camera) const {
	if (int(frames.size()) >= opts.max_keyframes) {
		return false;
	}
	const double cos_min = std::cos(opts.min_angle_deg * std::numbers::pi / 180.0);
	const glm::dvec3 direction = view_direction(p_world_from_camera);
	for (const Keyframe &k : frames) {
		const bool near = glm::length(k.world_from_camera.translation - p_world_from_camera.translation) < opts.min_distance_m;
		if (near && glm::dot(view_direction(k.world_from_camera), direction) > cos_min) {
			return false; // one keyframe sees much the same
		}
	}
	return true;
}

bool KeyframeDatabase::consider(const cv::Mat &p_depth_m, const cv::Mat &p_rgb, const Pose &p_world_from_camera) {
	if (!wants(p_world_from_camera)) {
		return false;
	}
	Keyframe k;
	k.id = int(frames.size());
	k.world_from_camera = p_world_from_camera;
	k.thumbnail = thumbnail(p_depth_m, p_rgb);
	if (!k.thumbnail.usable) {
		return false;
	}
	frames.push_back(std::move(k));
	return true;
}

double KeyframeDatabase::distance(const KeyframeThumbnail &p_a, const KeyframeThumbnail &p_b) const {
	if (!p_a.usable || !p_b.usable || p_a.depth_m.size() != p_b.depth_m.size()) {
		return -1.0;
	}
	double sum = 0.0;
	int both = 0;
	for (int r = 0; r < p_a.depth_m.rows; r++) {
		const float *da = p_a.depth_m.ptr<float>(r), *db = p_b.depth_m.ptr<float>(r);
		const float *ia = p_a.intensity.ptr<float>(r), *ib = p_b.intensity.ptr<float>(r);
		for (int c = 0; c < p_a.depth_m.cols; c++) {
			if (da[c] > 0.0f && db[c] > 0.0f) {
				sum += std::abs(double(da[c]) - db[c]) / opts.depth_scale_m + std::abs(double(ia[c]) - ib[c]);
				both++;
			}
		}
	}
	if (both < int(opts.min_overlap * double(p_a.depth_m.total()))) {
		return -1.0;
	}
	return sum / both;
}

std::vector<size_t> KeyframeDatabase::nearest(const KeyframeThumbnail &p_query, size_t p_count) const {
	std::vector<std::pair<double, size_t>> ranked;
	for (size_t i = 0; i < frames.size(); i++) {
		const double d = distance(p_query, frames[i].thumbnail);
		if (d >= 0.0) {
			ranked.emplace_back(d, i);
		}
	}
	std::sort(ranked.begin(), ranked.end());
	std::vector<size_t> out;
	for (size_t i = 0; i < ranked.size() && i < p_count; i++) {
		out.push_back(ranked[i].second);
	}
	return out;
}

} // namespace roomprobe
