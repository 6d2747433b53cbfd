#pragma once
// The rig's photometry: how a camera's 8-bit values become radiance, so that the coarse texture
// (fisheye) and the dense colours (RGB camera) are in one unit, that of the ground truth. The
// model is the synthetic rig's (synth/synth_renderer.h): value = sRGB(radiance * exposure *
// vignetting), clipped to 8 bits; vignetting is radial over the fisheye's image circle, falling to
// vignetting_edge_gain at its rim. Linearising inverts it: sRGB decoded, over the exposure, over
// the vignetting. Saturated values stay at the top of the range (they are clipped, not recovered).
//
// A rig whose photometry is not known (known == false) keeps the frames as recorded: an 8-bit
// value v becomes v / 255, the coarse texture's convention without calibration.

#include <camera/camera_params.h>
#include <io/opencv.h>

#include <glm/vec2.hpp>

#include <array>
#include <string>

namespace roomprobe {

struct RigPhotometry {
	bool known = false;
	double fisheye_exposure = 1.0; // radiance -> linear value, the fisheye's exposure and gain together
	double rgb_exposure = 1.0; // the same for the RGB camera
	double fisheye_vignetting_edge_gain = 1.0; // at the image circle's rim; 1: no vignetting
};

// The fisheye's radial vignetting at pixel p_pixel: 1 at the image circle's centre, p_edge_gain
// at its rim ((1 + k r^2)^-2 with r the radius over the circle's); 1 everywhere for a gain >= 1.
double radial_vignetting(const OmniParams &p_camera, const glm::dvec2 &p_pixel, double p_edge_gain);

// 8-bit value -> linear value over p_exposure: sRGB decoded, divided by the exposure.
std::array<float, 256> linearising_lut(double p_exposure);

// Reads the photometry that a synthetic recording states in its synth.yaml (fisheye_exposure,
// rgb_exposure, fisheye_vignetting_edge_gain). False, with r_error naming the file, when it
// cannot be read; true with known == false when the folder has no synth.yaml.
bool read_recording_photometry(const std::string &p_recording_folder, RigPhotometry *r_photometry, std::string *r_error);

// Turns fisheye frames into radiance with one photometry (the inverse vignetting is computed once
// per fisheye size). Frames that are not 8-bit (HDR, CV_32FC3) and all frames of an unknown
// photometry pass unchanged.
class FisheyeLinearizer {
public:
	void configure(const RigPhotometry &p_photometry, const OmniParams &p_fisheye);
	bool active() const { return photometry.known; }
	// CV_8UC1 or CV_8UC3 (R, G, B) -> CV_32FC3 radiance; other images as they are.
	cv::Mat linearise(const cv::Mat &p_image) const;
	const std::array<float, 256> &lut() const { return fisheye_lut; }

private:
	RigPhotometry photometry;
	std::array<float, 256> fisheye_lut{};
	cv::Mat inverse_vignetting; // CV_32FC1, the fisheye's size
};

} // namespace roomprobe
