#pragma once
// The parameters of RoomProbe's camera models: plain data, read from the rig file (rig/rig.h).
// Pixel coordinates: (0, 0) is the centre of the top-left pixel (OpenCV's convention).

namespace roomprobe {

// A pinhole camera with OpenCV's radial-tangential distortion (k1, k2, p1, p2, k3), for the
// RGB-D camera. Depth is registered to this camera, as on the paper's Xtion.
struct PinholeParams {
	int width = 0; // pixels
	int height = 0; // pixels
	double fx = 0.0, fy = 0.0; // focal lengths, pixels
	double cx = 0.0, cy = 0.0; // principal point, pixels
	double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0; // distortion, as cv::projectPoints
};

// The unified omnidirectional model (Mei; the same as Ying & Hu's sphere model, and
// cv::omnidir's) for the fisheye at run time, valid beyond 180 degrees: a point is projected to
// the unit sphere, then from a centre shifted by xi along the axis, then through a pinhole with
// radial-tangential distortion. The image circle bounds the pixels that see the scene.
struct OmniParams {
	int width = 0; // pixels
	int height = 0; // pixels
	double xi = 0.0; // mirror parameter (unitless); 0 is a pinhole, about 1 a wide fisheye
	double fx = 0.0, fy = 0.0; // generalised focal lengths, pixels
	double cx = 0.0, cy = 0.0; // principal point, pixels
	double skew = 0.0; // s in cv::omnidir's K (usually 0)
	double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0; // distortion, as cv::omnidir::projectPoints
	double circle_cx = 0.0, circle_cy = 0.0; // image-circle centre, pixels
	double circle_radius = 0.0; // image-circle radius, pixels; 0 means the whole image is valid
	double max_angle_deg = 0.0; // largest angle from the optical axis the lens sees; 0: no limit
};

} // namespace roomprobe
