#include "coarse_texture.h"

#include <algorithm>

namespace roomprobe {

CoarseTexture make_coarse_texture(const RoomMesh &p_mesh) {
	CoarseTexture texture;
	const int w = std::max(p_mesh.atlas_width, 0);
	const int h = std::max(p_mesh.atlas_height, 0);
	texture.color = cv::Mat(h, w, CV_32FC3, cv::Scalar(0.0, 0.0, 0.0));
	texture.observed = cv::Mat(h, w, CV_8UC1, cv::Scalar(0));
	texture.quality = cv::Mat(h, w, CV_32FC1, cv::Scalar(0.0));
	texture.updated = cv::Mat(h, w, CV_8UC1, cv::Scalar(0));
	texture.saturated = cv::Mat(h, w, CV_8UC1, cv::Scalar(0));
	texture.rgb_quality = cv::Mat(h, w, CV_32FC1, cv::Scalar(0.0));
	return texture;
}

} // namespace roomprobe
