#pragma once
// Depth preprocessing for ICP tracking (paper §4.2): valid-depth masking, a depth pyramid whose
// downsampling ignores holes and does not average across depth edges, and vertex and normal maps
// per level. The per-pixel work is in icp_kernels.h; these run it over images with
// cv::parallel_for_.

#include <io/opencv.h>

#include <camera/pinhole_camera.h>
#include <slam/slam_types.h>

#include <vector>

namespace roomprobe {

// p_depth_m (CV_32FC1 z in metres, or CV_16UC1 in units of p_depth_scale_m) as CV_32FC1 metres
// with NaN wherever there is no reading (0, NaN) or the depth lies outside
// [p_min_depth_m, p_max_depth_m]. r_valid_count (optional) gets the number of valid pixels.
cv::Mat clean_depth(const cv::Mat &p_depth_m, float p_min_depth_m, float p_max_depth_m, int *r_valid_count = nullptr,
		double p_depth_scale_m = 0.001);

// Half the size (rounded down) of a clean CV_32FC1 depth image: each pixel is the mean of the
// valid depths of its 2x2 block within p_band_m (metres) of the block's nearest one; NaN where
// the block has none.
cv::Mat downsample_depth(const cv::Mat &p_depth_m, float p_band_m);

// smooth_depth's spatial weights, (2 p_radius + 1)^2 row by row (also the GPU's, icp_reduce_gpu.h).
std::vector<float> smoothing_weights(int p_radius);

// Edge-preserving smoothing of a clean CV_32FC1 depth image (smooth_depth_pixel): Gaussian
// spatial weights of sigma 0.5 p_radius + 0.5 pixels over a (2 p_radius + 1)^2 window, only
// depths within p_band_m (metres) of the centre's; holes stay holes. p_radius 0: a copy.
cv::Mat smooth_depth(const cv::Mat &p_depth_m, int p_radius, float p_band_m);

// How a depth image becomes a surface (vertex and normal maps), for the frame and for
// make_model_maps alike.
struct SurfaceOptions {
	// Smoothing of the full-size depth before anything else (smooth_depth): sensor noise of several
	// millimetres over 1 cm pixels would otherwise tilt the normals by tens of degrees.
	int smoothing_radius_px = 2; // pixels; 0: no smoothing
	float smoothing_band_m = 0.04f; // metres
	float max_jump_relative = 0.05f; // no normal across a z step larger than this times z (unitless)
};

// CV_32FC3 camera-frame points (metres, OpenCV axes) of a CV_32FC1 depth image; NaN where the
// depth is NaN or <= 0.
cv::Mat compute_vertex_map(const cv::Mat &p_depth_m, const PinholeIntrinsics &p_camera);

// CV_32FC3 unit camera-frame normals of a vertex map, towards the camera; NaN at the border,
// next to holes and on depth edges (a neighbour more than p_max_jump_relative * z away in z).
// p_sample_stride > 1: only every p_sample_stride-th pixel of every p_sample_stride-th row (from
// (0, 0)) gets its normal, the others NaN (for ICP's sampled finest level).
cv::Mat compute_normal_map(const cv::Mat &p_vertices, float p_max_jump_relative, int p_sample_stride = 1);
// A raycast's normals from its points, as the frame's are from its vertices (compute_normal_map,
// in the camera's frame, turned back to the world's): KinectFusion's model normals. NaN where a
// neighbour has no point or lies across a depth edge.
void model_normals_from_points(ModelMaps *io_maps, float p_max_jump_relative);

// The local spread of a normal map (CV_32FC3, NaN where none): the mean, over the pixels whose
// 3x3 neighbourhood is whole, of |n - n3|^2, n3 the mean of those nine normals. A surface's shape
// changes little over three pixels and its noise does not, so on a young model it is mostly noise
// (DenseSlamOptions::young_model_noise_factor). 0 when no pixel qualifies.
double normal_spread(const cv::Mat &p_normals);

// CV_32FC1 intensity in [0, 1] (mean of R, G, B / 255) of a CV_8UC3 image; empty when it is empty.
cv::Mat intensity_of(const cv::Mat &p_rgb);

// One depth frame, level 0 the full size, level l at 1 / 2^l (PinholeIntrinsics::level).
struct FramePyramid {
	std::vector<PinholeIntrinsics> cameras;
	std::vector<cv::Mat> depth; // CV_32FC1 metres, NaN = none
	std::vector<cv::Mat> vertices; // CV_32FC3 camera frame, metres
	std::vector<cv::Mat> normals; // CV_32FC3 camera frame, unit; at level 0 only on the sampled pixels (build_frame_pyramid)
	std::vector<cv::Mat> intensity; // CV_32FC1 in [0, 1] (2x2 means); empty when no colour was given
};

// p_levels >= 1 levels of a clean depth image (clean_depth), smoothed first as p_surface says,
// and, optionally, its colour (CV_8UC3, may be empty). p_band_m as in downsample_depth. Level 0's
// normals only on every p_finest_stride-th pixel of every p_finest_stride-th row (the pixels ICP
// pairs there, IcpOptions::finest_stride_px); the coarser levels come from the whole of it.
FramePyramid build_frame_pyramid(const cv::Mat &p_clean_depth_m, const cv::Mat &p_rgb, const PinholeIntrinsics &p_camera, int p_levels,
		float p_band_m, const SurfaceOptions &p_surface, int p_finest_stride = 1);

} // namespace roomprobe
