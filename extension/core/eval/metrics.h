#pragma once
// Image-quality metrics between an estimated environment map and the ground truth (paper §5.3).
//
// PSNR: both cubemaps are tone-mapped exactly as the PNG nets are (envmap/export.h tone_map_srgb8:
// each linear channel clamped to [0, 1], sRGB-encoded, 0..255), then
//   PSNR = 10 log10(255^2 / MSE),
// MSE over every pixel of all six faces and the three channels together (every face pixel counts
// the same, not weighted by solid angle). Identical images (MSE = 0) give PSNR_CAP_DB rather than
// +inf, so that means over a sequence stay finite.
//
// SSIM (Wang, Bovik, Sheikh, Simoncelli, "Image quality assessment: from error visibility to
// structural similarity", IEEE TIP 13(4), 2004): on the luma of the tone-mapped 8-bit values
// (Y = 0.2126 R + 0.7152 G + 0.0722 B, range 0..255), with the paper's standard settings: an
// 11 x 11 circular-symmetric Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03, L = 255; the SSIM
// map's mean per face (OpenCV's GaussianBlur with replicated borders, so border pixels count),
// then the mean of the six faces.
//
// On the linear HDR values as well: PSNR with the ground truth's largest channel value as the
// peak, and the SSIM of linear luminance with L = that peak. That peak moves with the content: on
// real HDR content every variant then scores alike, so it is kept for comparison only.
//
// HDR PSNR with a fixed peak (psnr_mu_db): each linear channel x, in the RGB camera's linear unit
// (1 = its white at the reference exposure), is clamped to [0, HDR_PEAK] and compressed by the
// mu-law T(x) = ln(1 + MU_LAW x / HDR_PEAK) / ln(1 + MU_LAW), MU_LAW = 5000 (as in HDR video
// coding); PSNR = 10 log10(1 / MSE) over T in [0, 1]. HDR_PEAK = 64: six stops over white, above
// the synthetic scenes' lamps (about 25) and a sunlit window seen indoors.
//
// The worst directions (psnr_worst5_db): the tone-mapped PSNR over the 5 % of pixels (directions)
// whose error, averaged over the three channels, is largest.
//
// The irradiance error: what a diffuse (or PRT) object sees. Both maps are projected onto 5 bands
// of SH (envmap/spherical_harmonics.h) and convolved with the clamped cosine; the irradiance's
// luminance E(n) is evaluated at 64 normals n spread evenly over the sphere (a Fibonacci
// lattice), and the error is RMS(E_estimate - E_truth) / mean(E_truth): 0.05 is 5 %.

#include <envmap/cubemap.h>

namespace roomprobe {

inline constexpr double PSNR_CAP_DB = 100.0;
inline constexpr double HDR_PEAK = 64.0;
inline constexpr double MU_LAW = 5000.0;

struct CubemapMetrics {
	bool ok = false; // false: the cubemaps are invalid or of different sizes
	double psnr_db = 0.0; // tone-mapped 8-bit sRGB
	double ssim = 0.0; // tone-mapped 8-bit luma
	double psnr_linear_db = 0.0; // linear HDR, peak = the ground truth's largest value
	double ssim_linear = 0.0; // linear luminance, L = that peak
	double irradiance_error = 0.0; // relative, SH irradiance over 64 normals (above)
	double psnr_mu_db = 0.0; // HDR, mu-law over a fixed peak (above)
	double psnr_worst5_db = 0.0; // tone-mapped, the worst 5 % of directions (above)
};

// The tone-mapped 8-bit view of a face (CV_8UC3 R, G, B), as in the PNG net.
cv::Mat tone_map_face(const cv::Mat &p_linear_face);

// PSNR of 8-bit images of the same size and type (any channel count), capped at PSNR_CAP_DB.
double psnr_8bit(const std::vector<cv::Mat> &p_a, const std::vector<cv::Mat> &p_b);
// Mean SSIM of two single-channel CV_32F images (the same size), dynamic range p_range.
double ssim_gray(const cv::Mat &p_a, const cv::Mat &p_b, double p_range);

CubemapMetrics compare_cubemaps(const Cubemap &p_estimate, const Cubemap &p_ground_truth);

} // namespace roomprobe
