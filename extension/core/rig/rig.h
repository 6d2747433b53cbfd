#pragma once
// The rig: the RGB-D camera and the upward fisheye on one bracket, and its calibration file
// (YAML through cv::FileStorage; the schema is in calib/README.md).

#include <camera/camera_params.h>
#include <math/pose.h>
#include <rig/photometry.h>

#include <glm/vec3.hpp>

#include <limits>
#include <string>

namespace roomprobe {

struct Rig {
	PinholeParams rgb; // the RGB-D camera; depth is registered to it
	double depth_scale_m = 0.001; // metres per unit of the 16-bit depth images
	// Width and height 0: the rig has no fisheye (an RGB-D camera alone, for SLAM-only recordings
	// and datasets); then rgb_from_fisheye and fisheye_time_offset_s mean nothing.
	OmniParams fisheye;
	Pose rgb_from_fisheye; // fixed extrinsic: fisheye frame -> RGB-D camera frame
	double fisheye_time_offset_s = 0.0; // add to a fisheye timestamp to get RGB-D clock time
	// Live capture: how long before its arrival each camera took a frame (exposure, readout,
	// transfer), seconds in [0, 1]. A capture thread stamps a frame with the host's monotonic
	// clock less this (drivers/capture). Optional in the file; 0 when absent.
	double rgbd_latency_s = 0.0;
	double fisheye_latency_s = 0.0; // a rig without a fisheye leaves it 0
	// How the cameras' codes become radiance (rig/photometry.h); optional in the file (version 2),
	// unknown for version 1 files and rigs never calibrated photometrically.
	RigPhotometry photometry;

	bool has_fisheye() const { return fisheye.width != 0 || fisheye.height != 0; }
};

// How well a calibration fits its views: ./roomprobe calibrate writes it into the rig file as
// calibration_report, which load_rig accepts and does not read (it documents, it changes nothing).
// Reprojection errors are RMS pixels per corner; *_std is one standard deviation.
struct RigCalibrationReport {
	std::string board; // "9x6 inner corners, 35 mm squares"
	size_t rgb_views = 0, fisheye_views = 0, pair_views = 0; // used in the fits
	double rgb_rms_px = std::numeric_limits<double>::quiet_NaN();
	PinholeParams rgb_std;
	std::string fisheye_method; // "cv::omnidir::calibrate", or the OCamCalib file fitted
	double fisheye_rms_px = std::numeric_limits<double>::quiet_NaN();
	OmniParams fisheye_std;
	double pair_rgb_rms_px = std::numeric_limits<double>::quiet_NaN(), pair_fisheye_rms_px = std::numeric_limits<double>::quiet_NaN();
	glm::dvec3 rgb_from_fisheye_translation_std_m{ 0.0 };
	glm::dvec3 rgb_from_fisheye_rotation_std_deg{ 0.0 };
	bool depth_checked = false; // measured depth = depth_scale * board depth + depth_offset_m
	double depth_scale = 1.0, depth_offset_m = 0.0, depth_residual_rms_m = 0.0, depth_raw_rms_m = 0.0;
	size_t depth_samples = 0;
	std::string clock_offset; // how fisheye_time_offset_s was found
	// Photometric calibration (calibration/photometric_calibration.h), when it was done.
	std::string photometry; // how: "exposure sweep of N images, flat field, M pair views", or why not
	double response_fit_rms = std::numeric_limits<double>::quiet_NaN(); // Debevec's residual, ln units
	double vignetting_fit_rms = std::numeric_limits<double>::quiet_NaN(); // flat field against the table, relative
	double colour_fit_rms = std::numeric_limits<double>::quiet_NaN(); // fisheye against RGB on the board, relative
};

struct RigLoadResult {
	bool ok = false;
	std::string error; // names the file and the field, e.g. "calib/rig.yaml: fisheye.xi: missing"
	Rig rig;
};

// A file without the fisheye, rgb_from_fisheye and fisheye_time_offset_s fields (all three left
// out together) gives a rig without a fisheye.
RigLoadResult load_rig(const std::string &p_path);
// p_rig's RGB-D camera alone (issue #43): no fisheye, extrinsic, clock offset, latency or
// photometry (the file's photometry describes both cameras, check_rig); the RGB camera as it was.
Rig rgbd_camera_alone(const Rig &p_rig);
// Writes the rig file (without the fisheye's three fields when the rig has no fisheye); returns an empty string, or the error naming the file.
// With p_report, the calibration's report is written after the rig (calibration_report). Replaces
// p_path whole or leaves it as it was (io/replace_file.h).
std::string save_rig(const std::string &p_path, const Rig &p_rig, const RigCalibrationReport *p_report = nullptr);

// The version of the schema that save_rig writes (the roomprobe_rig field). Version 2 added the
// optional photometry; load_rig reads versions 1 and 2.
inline constexpr int RIG_FILE_VERSION = 2;
// A rotation in a rig file may be this far off unit norm (it is then normalised).
inline constexpr double RIG_UNIT_TOLERANCE = 1e-6;
// The largest image side a rig may declare, pixels (16K: beyond any RGB-D camera or fisheye).
inline constexpr int RIG_MAX_IMAGE_SIDE = 16384;
// Checks the values (positive sizes and focal lengths, finite numbers, a unit rotation, a lens
// angle the unified model can project; none of the fisheye's for a rig without one): an empty
// string, or "field: problem", e.g.
// "fisheye.fx: must be positive (got -1)". load_rig and save_rig both apply it.
std::string check_rig(const Rig &p_rig);

} // namespace roomprobe
