#pragma once
// The synthetic rig's ray tracer (Embree 4): renders a synth Scene as the RGB-D camera, the
// fisheye and a ground-truth cubemap would see it.
//
// Radiance along a ray = emitted + albedo * (ambient + E / pi), where E is the direct
// irradiance from the scene's lights with shadow rays (point lights: one ray; rect lights: a
// fixed stratified grid, so images are noise-free) and ambient a constant (plus each switched-on
// light's share). One bounce, no path tracing: fast and deterministic. Everything is linear HDR
// until a camera turns it into 8 bits.
//
// Pixel rays come from the camera models only (camera/pinhole_camera.h, camera/omni_camera.h).
// Images are cv::Mat in R, G, B order (not OpenCV's usual BGR), as recording/recording_types.h
// has them.

#include <io/opencv.h>

#include "synth_scene.h"

#include <camera/camera_params.h>
#include <math/pose.h>
#include <rig/photometry.h>


#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace roomprobe::synth {

struct Hit {
	bool hit = false;
	double distance = 0.0; // along the ray, in units of the direction's length
	glm::dvec3 point = glm::dvec3(0.0); // world
	glm::dvec3 normal = glm::dvec3(0.0); // unit shading normal, on the side the ray came from
	int material = -1;
	double u_m = 0.0, v_m = 0.0; // texture coordinates, metres
};

// The Embree scene of a synth Scene. Thread-safe for queries once built.
class SynthRenderer {
public:
	explicit SynthRenderer(const Scene &p_scene);
	~SynthRenderer();
	SynthRenderer(const SynthRenderer &) = delete;
	SynthRenderer &operator=(const SynthRenderer &) = delete;

	bool ok() const { return error_message.empty(); }
	const std::string &error() const { return error_message; }
	const Scene &scene() const { return scene_data; }
	size_t triangle_count() const { return triangles.size(); }

	// false: every surface is flat-lit (radiance = albedo + emission), for tests.
	void set_lighting_enabled(bool p_enabled) { lighting_enabled = p_enabled; }

	// The nearest surface along origin + t * direction, t in (t_near, t_far).
	Hit intersect(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near = 0.0, double p_t_far = 1e30) const;
	// Whether anything lies along origin + t * direction, t in (t_near, t_far).
	bool occluded(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_t_near, double p_t_far) const;
	// The radiance leaving a hit towards the ray's origin at time t (background for a miss).
	Color shade(const Hit &p_hit, const glm::dvec3 &p_direction, double p_time_s) const;
	Color radiance(const glm::dvec3 &p_origin, const glm::dvec3 &p_direction, double p_time_s, Hit *r_hit = nullptr) const;

private:
	struct TriangleInfo {
		int material = 0;
		int sphere = -1; // index into scene.spheres: smooth normal and spherical (u, v)
		glm::dvec3 origin = glm::dvec3(0.0), u_axis = glm::dvec3(0.0), v_axis = glm::dvec3(0.0);
		glm::dvec3 normal = glm::dvec3(0.0);
	};
	struct LightSample {
		int light = 0;
		glm::dvec3 position = glm::dvec3(0.0);
		double weight = 1.0; // Rect: area / samples
	};
	struct Embree;

	void add_triangle(const glm::dvec3 &p_a, const glm::dvec3 &p_b, const glm::dvec3 &p_c, const TriangleInfo &p_info);
	void add_quad(const Quad &p_quad);
	Color emission(const Material &p_material, const Hit &p_hit, const glm::dvec3 &p_direction, double p_time_s) const;

	Scene scene_data;
	std::string error_message;
	bool lighting_enabled = true;
	std::vector<float> vertices; // x, y, z per vertex
	std::vector<uint32_t> indices;
	std::vector<TriangleInfo> triangles;
	std::vector<LightSample> light_samples;
	std::unique_ptr<Embree> embree;
};

// ---------------------------------------------------------------- tone mapping

// 8-bit sRGB of linear values times exposure, clipped (saturates at 1). CV_32FC3 -> CV_8UC3.
cv::Mat to_srgb8(const cv::Mat &p_linear, double p_exposure = 1.0);
// 8-bit codes of linear values times each channel's gain through a tone curve, clipped.
cv::Mat encode_8bit(const cv::Mat &p_linear, ToneCurve p_curve, const glm::dvec3 &p_channel_gains);
uint8_t linear_to_srgb8(float p_linear);
float srgb8_to_linear(uint8_t p_code);

// ---------------------------------------------------------------- the RGB-D camera

// Kinect-like axial noise (Nguyen et al. 2012): sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres,
// slam_types.h's DepthNoiseModel with its defaults.
double kinect_depth_sigma_m(double p_z_m);

struct RgbdOptions {
	double exposure = 1.0;
	int samples_per_axis = 1; // colour antialiasing: n x n rays a pixel (depth uses the centre)
	bool depth_noise = true; // axial Gaussian noise, kinect_depth_sigma_m
	uint64_t noise_seed = 0; // the noise is a hash of (seed, pixel): same seed, same image
	double min_depth_m = 0.4, max_depth_m = 8.0; // no reading outside
	double grazing_angle_deg = 75.0; // no reading where ray and normal are further apart
	// No reading on the far side of a depth discontinuity: a pixel whose 8-neighbour is nearer
	// by more than max(edge_jump_m, edge_jump_relative * z).
	double edge_jump_m = 0.04;
	double edge_jump_relative = 0.03;
	// No reading where the IR projector, this far along the camera's +x, cannot see the surface
	// (the Kinect's projector shadow). 0: off.
	double projector_baseline_m = 0.075;
};

struct RgbdImage {
	cv::Mat rgb; // CV_8UC3 sRGB, R, G, B
	cv::Mat depth; // CV_16UC1, units of depth_scale_m, 0 = no reading
	cv::Mat depth_true_m; // CV_32FC1, noise-free z in the camera frame (0 where nothing was hit)
	cv::Mat radiance; // CV_32FC3 linear, R, G, B, before exposure
};

// Depth is z in the camera frame (OpenCV frame), as an Xtion registered to RGB gives it.
RgbdImage render_rgbd(const SynthRenderer &p_renderer, const PinholeParams &p_camera, double p_depth_scale_m,
		const Pose &p_world_from_camera, double p_time_s, const RgbdOptions &p_options);

// ---------------------------------------------------------------- the fisheye

struct FisheyeOptions {
	double exposure = 1.0;
	int samples_per_axis = 1; // n x n rays a pixel; subsamples outside the image circle count as black
	// Vignetting 1 / (1 + k r^2)^2 (cos^4-like), r = distance from the circle centre / radius,
	// k chosen so that the gain at the circle's edge is this. 1: none.
	double vignetting_edge_gain = 0.5;
	// The 8-bit image's photometry (rig/photometry.h): code = tone_curve(radiance * exposure *
	// vignetting * channel_gains), clipped. The gains are the fisheye's white balance, which the
	// RGB camera does not share (calibration's colour transform undoes them).
	ToneCurve tone_curve = ToneCurve::Srgb;
	glm::dvec3 channel_gains{ 1.0 };
};

struct FisheyeImage {
	cv::Mat image; // CV_8UC3 through the tone curve, with saturation, R, G, B; black outside the image circle
	cv::Mat radiance; // CV_32FC3 linear R, G, B: exposure and vignetting applied, not clipped (the HDR frame)
};

// The rig's vignetting model (rig/photometry.h), which the renderer applies and calibration inverts.
inline double fisheye_vignetting(const OmniParams &p_camera, const glm::dvec2 &p_pixel, double p_edge_gain) {
	return radial_vignetting(p_camera, p_pixel, p_edge_gain);
}

FisheyeImage render_fisheye(const SynthRenderer &p_renderer, const OmniParams &p_camera, const Pose &p_world_from_camera,
		double p_time_s, const FisheyeOptions &p_options);

// ---------------------------------------------------------------- ground-truth cubemaps

// Six CV_32FC3 faces (linear HDR radiance, R, G, B) of size x size at a world position and time,
// in the face order and orientation of types/cubemap_layout.h (cubemap_direction there).
std::array<cv::Mat, 6> render_cubemap(const SynthRenderer &p_renderer, const glm::dvec3 &p_position, double p_time_s, int p_size);

// ---------------------------------------------------------------- helpers

// A hash of two 64-bit values (splitmix64): per-frame seeds from a sequence seed.
uint64_t mix_seed(uint64_t p_a, uint64_t p_b);

} // namespace roomprobe::synth
