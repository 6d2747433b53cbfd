#pragma once
// Real spherical harmonics up to band 4 (5 bands, 25 coefficients per colour channel), for
// projecting environment maps for diffuse PRT lighting (paper §4.8: "5 bands of SH").
//
// Basis: the standard real SH of Sloan's "Stupid Spherical Harmonics (SH) Tricks" (2008),
// orthonormal over the sphere (integral of y_i y_j over all directions = delta_ij), WITH the
// Condon-Shortley phase, written in the world's own Cartesian components of the unit direction
// d = (x, y, z), exactly as Sloan's polynomial table reads (so the "pole" of the m = 0 functions
// is world +Z, not world up +Y):
//   y_l^m = sqrt(2) K_l^m cos(m phi) P_l^m(cos theta)     m > 0
//   y_l^0 =         K_l^0 P_l^0(cos theta)
//   y_l^m = sqrt(2) K_l^m sin(|m| phi) P_l^|m|(cos theta) m < 0
// with cos theta = z, phi = atan2(y, x), K_l^m = sqrt((2l + 1) / (4 pi) (l - |m|)! / (l + |m|)!)
// and P_l^m the associated Legendre polynomials including (-1)^m. For example
//   y_0^0 = 1 / (2 sqrt(pi)),  y_1^-1 = -sqrt(3 / (4 pi)) y,  y_1^0 = sqrt(3 / (4 pi)) z,
//   y_1^1 = -sqrt(3 / (4 pi)) x,  y_2^-2 = sqrt(15 / (4 pi)) x y, ...
// Ordering: coefficient index i = l (l + 1) + m, l = 0..4, m = -l..l (0: y_0^0; 1..3: y_1^-1,
// y_1^0, y_1^1; 4..8: band 2; 9..15: band 3; 16..24: band 4).

#include "cubemap.h"

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <memory>
#include <vector>

namespace roomprobe {

inline constexpr int SH_BANDS = 5;
inline constexpr int SH_COEFFICIENTS = SH_BANDS * SH_BANDS; // 25

// Index of y_l^m in the arrays below.
constexpr int sh_index(int p_l, int p_m) {
	return p_l * (p_l + 1) + p_m;
}

// One R, G, B triple per basis function, in the order above.
using ShCoefficients = std::array<glm::dvec3, SH_COEFFICIENTS>;

// The 25 basis functions at direction p_direction (normalised here; must be non-zero).
std::array<double, SH_COEFFICIENTS> sh_basis(const glm::dvec3 &p_direction);

// Projects a cubemap onto the basis: c_i = sum over texels of L(texel) y_i(d) dOmega, with
// d the texel centre's direction (cubemap_direction) and dOmega its exact solid angle
// (cubemap_texel_solid_angle). A cubemap that is not is_valid_cubemap gives all zeros.
// Parallel over face rows (TBB), deterministic. Faces larger than p_max_face_size are first
// box-filtered (cv::INTER_AREA) to that size (0: always the full faces); the per-texel
// y_i dOmega of each size is computed once and kept.
inline constexpr int SH_PROJECTION_FACE_SIZE = 64;
ShCoefficients project_sh(const Cubemap &p_cubemap, int p_max_face_size = SH_PROJECTION_FACE_SIZE);
// project_sh's parts, shared with its GPU twin (sh_project_gpu.h): the faces it projects (box-
// filtered to p_max_face_size when larger), and y_i dOmega of every texel of a p_size cubemap,
// [face][v][u][i] (kept per size, like project_sh's).
std::array<cv::Mat, 6> sh_projection_faces(const Cubemap &p_cubemap, int p_max_face_size = SH_PROJECTION_FACE_SIZE);
std::shared_ptr<const std::vector<float>> sh_texel_weights(int p_size);

// sum_i c_i y_i(p_direction): the band-limited function at a direction.
glm::dvec3 evaluate_sh(const ShCoefficients &p_coefficients, const glm::dvec3 &p_direction);

// The cosine-lobe factor A_l of band l (Ramamoorthi and Hanrahan 2001): pi, 2 pi / 3, pi / 4,
// 0, -pi / 24 for l = 0..4.
double sh_cosine_lobe_factor(int p_l);

// Irradiance from radiance: multiplies each band by A_l, so that evaluate_sh of the result at a
// unit normal n gives E(n) = integral of L(d) max(0, n . d) dOmega (exact for radiance that is
// band-limited to 5 bands; band 4 of the clamped cosine truncated beyond). Divide by pi for the
// exit radiance of a white Lambertian surface.
ShCoefficients convolve_cosine_lobe(const ShCoefficients &p_radiance);

// The coefficients of the same function seen in a rotated frame: g(d) = f(p_rotation d). With
// p_rotation a frame's basis in world coordinates (an object's rotation), g is the world
// function written in that frame's directions: what a PRT transfer in the object's frame is
// dotted with. Exact (each band is closed under rotation), band by band from the basis at
// fixed directions.
ShCoefficients rotate_sh(const ShCoefficients &p_coefficients, const glm::dmat3 &p_rotation);

} // namespace roomprobe
