#pragma once
// An environment map as a cubemap (paper §4.7): six square CV_32FC3 faces of linear R, G, B,
// in the project's one cubemap convention (types/cubemap_layout.h: face order +X -X +Y -Y
// +Z -Z, world Y up, cubemap_direction / cubemap_face_pixel for the pixel <-> direction map).

#include <io/opencv.h>

#include <array>

#include <types/cubemap_layout.h>
#include <recording/recording_types.h>

namespace roomprobe {

struct Cubemap {
	int size = 0; // face width and height, pixels
	CubemapFaces faces; // each size x size, CV_32FC3, linear R, G, B
	// Optional (empty when unknown): for each face pixel, the distance in metres from the map's
	// centre to the surface it shows (CV_32FC1, size x size; 0: nothing there). The coarse and
	// dense renders fill it; distance-aware reflections (envmap/parallax.h) read it.
	std::array<cv::Mat, 6> distance_m;
};

// Whether p_cubemap carries distances (six size-square CV_32FC1 faces).
bool has_distances(const Cubemap &p_cubemap);

// A p_size x p_size cubemap filled with p_fill.
Cubemap make_cubemap(int p_size, const cv::Vec3f &p_fill = cv::Vec3f(0.0f, 0.0f, 0.0f));

// A copy with pixels of its own (a Cubemap's copy shares them, as cv::Mat does).
Cubemap clone_cubemap(const Cubemap &p_cubemap);

// Whether p_cubemap has six p_cubemap.size-square CV_32FC3 faces (size > 0).
bool is_valid_cubemap(const Cubemap &p_cubemap);

// Whether two images hold the same pixels, bit for bit (two empty ones do).
bool same_pixels(const cv::Mat &p_a, const cv::Mat &p_b);

// A bit per face (1 << face) whose colours differ between two valid cubemaps, bit for bit; all
// six when their sizes differ.
uint8_t cubemap_changed_faces(const Cubemap &p_a, const Cubemap &p_b);

// The exact solid angle (steradians) that face pixel (p_u, p_v) of a p_size face subtends;
// the same for every face. The 6 p_size^2 pixels sum to 4 pi.
double cubemap_texel_solid_angle(int p_u, int p_v, int p_size);

// The four texels and weights of a bilinear read along p_direction (non-zero) on p_size faces,
// within the face the direction lands on (clamped at its edges, not across them).
struct CubemapBilinear {
	int face = 0;
	std::array<int, 4> x{}, y{};
	std::array<double, 4> weight{};
};
CubemapBilinear cubemap_bilinear(const glm::dvec3 &p_direction, int p_size);

// The map along p_direction (non-zero): cubemap_bilinear's read.
glm::dvec3 sample_cubemap(const Cubemap &p_cubemap, const glm::dvec3 &p_direction);

} // namespace roomprobe
