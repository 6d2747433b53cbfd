#pragma once
// The rig's photometry: how each camera's 8-bit codes become radiance, so that the coarse texture
// (fisheye) and the dense colours (RGB camera) are linear radiance in one unit. Per channel c:
//
//   radiance_c = channel_gains_c * response_c[code_c] / exposure_ratio / vignetting(r)
//
//   response      the inverse camera response (Debevec-Malik): the linear value of each code;
//   exposure_ratio the frame's exposure time and gain over the reference ones the gains were fitted
//                 at (1 where a frame's exposure is unknown);
//   vignetting    the fisheye's radial fall-off over its image circle (r = radius / circle radius);
//   channel_gains the colour transform into the rig's unit, which is the RGB camera's linear value
//                 at its own exposure (a diagonal transform: what a grey board fixes).
//
// A code at or above saturation_code in any channel is clipped: its radiance is a lower bound,
// and the coarse texture never lets it replace an unclipped observation (coarse/texture_update.h).
//
// ./roomprobe calibrate fits these (calibration/photometric_calibration.h); the rig file stores
// them (rig.h, schema version 2); a synthetic recording states its truth in synth.yaml
// (read_recording_photometry). A rig whose photometry is not known keeps the frames as recorded:
// an 8-bit value v becomes v / 255.

#include <camera/camera_params.h>
#include <io/opencv.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <limits>
#include <string>
#include <vector>

namespace roomprobe {

using ResponseCurve = std::array<float, 256>; // linear value of each 8-bit code

// One camera's photometric model (plain data).
struct CameraPhotometry {
	std::array<ResponseCurve, 3> response{}; // R, G, B; non-decreasing, response[c][0] >= 0
	// The fisheye's vignetting: the gain at radius i / (n - 1) of the image circle, linear in
	// between, the last value beyond the rim; vignetting[0] = 1. Empty: none (the RGB camera).
	std::vector<float> vignetting;
	glm::dvec3 channel_gains{ 1.0 }; // R, G, B: into the rig's radiance unit
	// The exposure time (microseconds) and gain (dB) the channel gains hold at; NaN: a frame's
	// exposure is not used (every frame at the reference).
	double reference_exposure_us = std::numeric_limits<double>::quiet_NaN();
	double reference_gain_db = 0.0;
	int saturation_code = 250; // a code >= this in any channel is clipped (1..255)
};

struct RigPhotometry {
	bool known = false;
	CameraPhotometry fisheye;
	CameraPhotometry rgb;
};

// Checks the values: "fisheye.response_g[17]: must not be less than the code below it", ...
// Empty when fine. An unknown photometry is always fine.
std::string check_photometry(const RigPhotometry &p_photometry);

// ---------------------------------------------------------------- tone curves

// Tone curves the synthetic rig encodes with (synth/synth_renderer.h); their inverses are its
// truth. Srgb: IEC 61966-2-1. Log: code / 255 = ln(1 + 30 x) / ln 31 (a camera's log profile).
enum class ToneCurve {
	Srgb,
	Log,
};
const char *tone_curve_name(ToneCurve p_curve);
bool parse_tone_curve(const std::string &p_name, ToneCurve *r_curve);
// Linear value (clipped to [0, 1]) -> 8-bit code, rounded.
uint8_t encode_tone(ToneCurve p_curve, float p_linear);
// The linear value of each code (its exact inverse at code / 255).
ResponseCurve tone_curve_response(ToneCurve p_curve);

// A camera whose codes are p_curve of (radiance * exposure * channel gain): its photometry in
// radiance units (channel_gains = 1 / (exposure * gain)).
CameraPhotometry tone_curve_photometry(ToneCurve p_curve, double p_exposure, const glm::dvec3 &p_channel_gains = glm::dvec3(1.0));

// ---------------------------------------------------------------- vignetting

// The synthetic fisheye's radial vignetting at pixel p_pixel: 1 at the image circle's centre,
// p_edge_gain at its rim ((1 + k r^2)^-2 with r the radius over the circle's); 1 everywhere for a
// gain >= 1.
double radial_vignetting(const OmniParams &p_camera, const glm::dvec2 &p_pixel, double p_edge_gain);
// Its table (CameraPhotometry::vignetting) with p_nodes values; empty for a gain >= 1.
std::vector<float> radial_vignetting_table(double p_edge_gain, int p_nodes = 33);
// A pixel's radius over the image circle's (image half-diagonal about the principal point
// without a circle).
double circle_radius_fraction(const OmniParams &p_camera, const glm::dvec2 &p_pixel);
// The table's gain at a radius fraction (1 for an empty table).
double vignetting_at(const std::vector<float> &p_table, double p_radius_fraction);

// ---------------------------------------------------------------- frames

// A frame's exposure over the reference: (exposure_us / reference) * 10^((gain_db - reference) / 20);
// 1 where either exposure is unknown (NaN), a NaN gain counting as the reference's.
double exposure_ratio(const CameraPhotometry &p_camera, double p_exposure_us, double p_gain_db);

// The photometry a recording's frames are linearised with: the truth a synthetic recording
// states in its synth.yaml (tone curves, exposures, vignetting, channel gains), else p_rig, the
// recording's rig file's (unknown for a version 1 file). False, with r_error naming the file, when
// synth.yaml is there but cannot be read, or states a ratio (an exposure, the vignetting edge gain
// or a channel gain) outside [1e-6, 1e6] or a photometry that check_photometry refuses.
bool read_recording_photometry(const std::string &p_recording_folder, const RigPhotometry &p_rig, RigPhotometry *r_photometry, std::string *r_error);

// A linearised fisheye frame.
struct LinearFrame {
	cv::Mat radiance; // CV_32FC3, R, G, B
	cv::Mat saturated; // CV_8UC1, 255 where a channel was clipped; empty when nothing can clip (HDR input)
};

// Turns fisheye frames into radiance with one photometry (the inverse vignetting is computed once
// per fisheye size). Frames that are not 8-bit (HDR, CV_32FC3) and all frames of an unknown
// photometry pass unchanged, without a saturation mask.
class FisheyeLinearizer {
public:
	void configure(const RigPhotometry &p_photometry, const OmniParams &p_fisheye);
	bool active() const { return known; }
	// CV_8UC1 or CV_8UC3 (R, G, B) -> radiance, at p_exposure_ratio (exposure_ratio()).
	LinearFrame linearise(const cv::Mat &p_image, double p_exposure_ratio = 1.0) const;
	// The radiance of code p_code at the image circle's centre at the reference exposure (for
	// thresholds), channel G.
	float centre_radiance(int p_code) const;

private:
	bool known = false;
	CameraPhotometry camera;
	std::array<ResponseCurve, 3> scaled{}; // response * channel gain
	cv::Mat inverse_vignetting; // CV_32FC1, the fisheye's size
};

// The RGB camera's 8-bit value -> radiance, for the dense colours (envmap/dense_render.h), which
// keep one curve for all three channels: channel G's response times its gain. Null-equivalent
// (value / 255) for an unknown photometry.
ResponseCurve rgb_radiance_lut(const RigPhotometry &p_photometry);

} // namespace roomprobe
