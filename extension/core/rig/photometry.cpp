#include "photometry.h"

#include <io/yaml_fields.h>
#include <parallel/parallel_for.h>

#include <math/srgb.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace roomprobe {

namespace {

constexpr double LOG_CURVE_A = 30.0;
// The range of synth.yaml's ratios (exposures, vignetting edge gain, channel gains): the synthetic
// rig writes them near 1 (--fisheye-gains within (0, 10], --vignetting within (0, 1]).
constexpr double SYNTH_RATIO_MIN = 1e-6;
constexpr double SYNTH_RATIO_MAX = 1e6;

const char *CHANNEL_NAMES[3] = { "r", "g", "b" };

} // namespace

std::string check_photometry(const RigPhotometry &p_photometry) {
	if (!p_photometry.known) {
		return std::string();
	}
	const std::pair<const char *, const CameraPhotometry *> cameras[] = { { "fisheye", &p_photometry.fisheye }, { "rgb", &p_photometry.rgb } };
	for (const auto &[name, camera] : cameras) {
		const std::string prefix = std::string("photometry.") + name + ".";
		for (int c = 0; c < 3; c++) {
			const ResponseCurve &curve = camera->response[size_t(c)];
			for (size_t k = 0; k < curve.size(); k++) {
				const std::string field = prefix + "response_" + CHANNEL_NAMES[c] + "[" + std::to_string(k) + "]";
				if (!std::isfinite(curve[k]) || curve[k] < 0.0f) {
					return field + ": must be a finite number >= 0 (got " + std::to_string(curve[k]) + ")";
				}
				if (k > 0 && curve[k] < curve[k - 1]) {
					return field + ": must not be less than the code below it (a response only rises)";
				}
			}
			if (!(curve[255] > 0.0f)) {
				return prefix + "response_" + CHANNEL_NAMES[c] + "[255]: must be positive";
			}
			const double gain = camera->channel_gains[c];
			if (!std::isfinite(gain) || gain <= 0.0) {
				return prefix + "channel_gains[" + std::to_string(c) + "]: must be a positive number (got " + std::to_string(gain) + ")";
			}
		}
		for (size_t i = 0; i < camera->vignetting.size(); i++) {
			const float v = camera->vignetting[i];
			if (!std::isfinite(v) || v <= 0.0f || v > 10.0f) {
				return prefix + "vignetting[" + std::to_string(i) + "]: must be within (0, 10] (got " + std::to_string(v) + ")";
			}
		}
		if (camera->vignetting.size() == 1) {
			return prefix + "vignetting: needs at least 2 values (centre and rim), or none";
		}
		if (!camera->vignetting.empty() && std::abs(camera->vignetting[0] - 1.0f) > 1e-4f) {
			return prefix + "vignetting[0]: must be 1 (the gain at the image circle's centre)";
		}
		if (!std::isnan(camera->reference_exposure_us) && !(camera->reference_exposure_us > 0.0 && std::isfinite(camera->reference_exposure_us))) {
			return prefix + "reference_exposure_us: must be a positive number of microseconds, or left out";
		}
		if (!std::isfinite(camera->reference_gain_db)) {
			return prefix + "reference_gain_db: must be a finite number";
		}
		if (camera->saturation_code < 1 || camera->saturation_code > 255) {
			return prefix + "saturation_code: must be within 1 to 255 (got " + std::to_string(camera->saturation_code) + ")";
		}
	}
	return std::string();
}

// ---------------------------------------------------------------- tone curves

const char *tone_curve_name(ToneCurve p_curve) {
	return p_curve == ToneCurve::Log ? "log" : "srgb";
}

bool parse_tone_curve(const std::string &p_name, ToneCurve *r_curve) {
	if (p_name == "srgb") {
		*r_curve = ToneCurve::Srgb;
	} else if (p_name == "log") {
		*r_curve = ToneCurve::Log;
	} else {
		return false;
	}
	return true;
}

uint8_t encode_tone(ToneCurve p_curve, float p_linear) {
	if (!(p_linear > 0.0f)) {
		return 0; // also NaN
	}
	const double x = std::min(double(p_linear), 1.0);
	const double v = p_curve == ToneCurve::Log ? std::log1p(LOG_CURVE_A * x) / std::log1p(LOG_CURVE_A) : srgb_encode(x);
	return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

ResponseCurve tone_curve_response(ToneCurve p_curve) {
	ResponseCurve curve{};
	for (int k = 0; k < 256; k++) {
		const double v = k / 255.0;
		curve[size_t(k)] = float(p_curve == ToneCurve::Log ? std::expm1(v * std::log1p(LOG_CURVE_A)) / LOG_CURVE_A : srgb_decode(v));
	}
	return curve;
}

CameraPhotometry tone_curve_photometry(ToneCurve p_curve, double p_exposure, const glm::dvec3 &p_channel_gains) {
	CameraPhotometry camera;
	const ResponseCurve curve = tone_curve_response(p_curve);
	camera.response = { curve, curve, curve };
	for (int c = 0; c < 3; c++) {
		camera.channel_gains[c] = 1.0 / (p_exposure * p_channel_gains[c]);
	}
	return camera;
}

// ---------------------------------------------------------------- vignetting

double circle_radius_fraction(const OmniParams &p_camera, const glm::dvec2 &p_pixel) {
	double radius = p_camera.circle_radius;
	double cx = p_camera.circle_cx, cy = p_camera.circle_cy;
	if (radius <= 0.0) {
		cx = p_camera.cx;
		cy = p_camera.cy;
		radius = 0.5 * std::hypot(p_camera.width, p_camera.height);
	}
	return std::hypot(p_pixel.x - cx, p_pixel.y - cy) / radius;
}

namespace {

double radial_vignetting_at(double p_radius_fraction, double p_edge_gain) {
	if (!(p_edge_gain > 0.0) || p_edge_gain >= 1.0) {
		return 1.0;
	}
	const double k = std::sqrt(1.0 / p_edge_gain) - 1.0;
	const double f = 1.0 + k * p_radius_fraction * p_radius_fraction;
	return 1.0 / (f * f);
}

} // namespace

double radial_vignetting(const OmniParams &p_camera, const glm::dvec2 &p_pixel, double p_edge_gain) {
	return radial_vignetting_at(circle_radius_fraction(p_camera, p_pixel), p_edge_gain);
}

std::vector<float> radial_vignetting_table(double p_edge_gain, int p_nodes) {
	std::vector<float> table;
	if (!(p_edge_gain > 0.0) || p_edge_gain >= 1.0 || p_nodes < 2) {
		return table;
	}
	for (int i = 0; i < p_nodes; i++) {
		table.push_back(float(radial_vignetting_at(double(i) / (p_nodes - 1), p_edge_gain)));
	}
	return table;
}

double vignetting_at(const std::vector<float> &p_table, double p_radius_fraction) {
	if (p_table.size() < 2) {
		return 1.0;
	}
	const double position = std::clamp(p_radius_fraction, 0.0, 1.0) * double(p_table.size() - 1);
	const size_t i = std::min(size_t(position), p_table.size() - 2);
	const double t = position - double(i);
	return (1.0 - t) * p_table[i] + t * p_table[i + 1];
}

// ---------------------------------------------------------------- frames

double exposure_ratio(const CameraPhotometry &p_camera, double p_exposure_us, double p_gain_db) {
	if (!(p_exposure_us > 0.0) || !std::isfinite(p_exposure_us) || !(p_camera.reference_exposure_us > 0.0)) {
		return 1.0;
	}
	const double gain_db = std::isfinite(p_gain_db) ? p_gain_db : p_camera.reference_gain_db;
	return p_exposure_us / p_camera.reference_exposure_us * std::pow(10.0, (gain_db - p_camera.reference_gain_db) / 20.0);
}

bool read_recording_photometry(const std::string &p_recording_folder, const RigPhotometry &p_rig, RigPhotometry *r_photometry, std::string *r_error) {
	*r_photometry = p_rig;
	const std::filesystem::path path = std::filesystem::path(p_recording_folder) / "synth.yaml";
	std::error_code ec;
	if (!std::filesystem::exists(path, ec)) {
		return true;
	}
	*r_photometry = RigPhotometry();
	try {
		cv::FileStorage info;
		const std::string problem = open_yaml_file(path.string(), &info);
		if (!problem.empty()) {
			*r_error = problem;
			return false;
		}
		double fisheye_exposure = 1.0, rgb_exposure = 1.0, edge_gain = 1.0, reference_us = std::numeric_limits<double>::quiet_NaN();
		const std::pair<const char *, double *> fields[] = { { "fisheye_exposure", &fisheye_exposure }, { "rgb_exposure", &rgb_exposure },
			{ "fisheye_vignetting_edge_gain", &edge_gain }, { "fisheye_reference_exposure_us", &reference_us } };
		// The exposures, the edge gain and the channel gains are ratios: within [1e-6, 1e6]. Any
		// positive number was taken, and 1e-310 or 1e300 made channel gains (1 / (exposure *
		// gain)) of inf or 0 and an edge gain of 1e-300 a vignetting table of zeros: photometry
		// that check_photometry refuses, used as the truth (found by fuzzing synth.yaml).
		const auto ratio = [](double p_value) { return p_value >= SYNTH_RATIO_MIN && p_value <= SYNTH_RATIO_MAX; };
		for (const auto &[name, value] : fields) {
			if (info[name].empty()) {
				continue;
			}
			*value = double(info[name]);
			const bool is_ratio = value != &reference_us;
			if (!std::isfinite(*value) || *value <= 0.0 || (is_ratio && !ratio(*value))) {
				*r_error = path.string() + ": " + name + ": must be a positive number" + (is_ratio ? " within [1e-6, 1e6]" : "");
				return false;
			}
		}
		ToneCurve fisheye_curve = ToneCurve::Srgb, rgb_curve = ToneCurve::Srgb;
		const std::pair<const char *, ToneCurve *> curves[] = { { "fisheye_tone_curve", &fisheye_curve }, { "rgb_tone_curve", &rgb_curve } };
		for (const auto &[name, curve] : curves) {
			if (!info[name].empty() && !parse_tone_curve(std::string(info[name]), curve)) {
				*r_error = path.string() + ": " + name + ": must be srgb or log";
				return false;
			}
		}
		glm::dvec3 gains(1.0);
		const cv::FileNode gains_node = info["fisheye_channel_gains"];
		if (!gains_node.empty()) {
			if (!gains_node.isSeq() || gains_node.size() != 3) {
				*r_error = path.string() + ": fisheye_channel_gains: must be a list of 3 positive numbers";
				return false;
			}
			for (int c = 0; c < 3; c++) {
				gains[c] = double(gains_node[c]);
				if (!std::isfinite(gains[c]) || !ratio(gains[c])) {
					*r_error = path.string() + ": fisheye_channel_gains[" + std::to_string(c) + "]: must be a positive number within [1e-6, 1e6]";
					return false;
				}
			}
		}
		RigPhotometry p;
		p.known = true;
		p.fisheye = tone_curve_photometry(fisheye_curve, fisheye_exposure, gains);
		p.fisheye.vignetting = radial_vignetting_table(edge_gain);
		p.fisheye.reference_exposure_us = reference_us;
		p.rgb = tone_curve_photometry(rgb_curve, rgb_exposure);
		// What the rig file would refuse is not taken as the truth either.
		const std::string invalid = check_photometry(p);
		if (!invalid.empty()) {
			*r_error = path.string() + ": the photometry it states is not valid: " + invalid;
			return false;
		}
		*r_photometry = p;
		return true;
	} catch (const cv::Exception &e) {
		*r_error = path.string() + ": " + e.what();
		return false;
	}
}

void FisheyeLinearizer::configure(const RigPhotometry &p_photometry, const OmniParams &p_fisheye) {
	known = p_photometry.known;
	camera = p_photometry.fisheye;
	inverse_vignetting.release();
	if (!known) {
		return;
	}
	for (int c = 0; c < 3; c++) {
		for (size_t k = 0; k < 256; k++) {
			scaled[size_t(c)][k] = float(camera.response[size_t(c)][k] * camera.channel_gains[c]);
		}
	}
	inverse_vignetting.create(p_fisheye.height, p_fisheye.width, CV_32FC1);
	for (int y = 0; y < p_fisheye.height; y++) {
		float *row = inverse_vignetting.ptr<float>(y);
		for (int x = 0; x < p_fisheye.width; x++) {
			const double v = vignetting_at(camera.vignetting, circle_radius_fraction(p_fisheye, glm::dvec2(x, y)));
			row[x] = v > 1e-6 ? float(1.0 / v) : 0.0f;
		}
	}
}

float FisheyeLinearizer::centre_radiance(int p_code) const {
	return known ? scaled[1][size_t(std::clamp(p_code, 0, 255))] : float(std::clamp(p_code, 0, 255)) / 255.0f;
}

LinearFrame FisheyeLinearizer::linearise(const cv::Mat &p_image, double p_exposure_ratio) const {
	LinearFrame frame;
	if (!known || p_image.depth() != CV_8U || p_image.size() != inverse_vignetting.size()) {
		frame.radiance = p_image;
		return frame;
	}
	cv::Mat rgb = p_image;
	if (p_image.channels() == 1) {
		cv::cvtColor(p_image, rgb, cv::COLOR_GRAY2RGB);
	}
	const float over_exposure = p_exposure_ratio > 0.0 && std::isfinite(p_exposure_ratio) ? float(1.0 / p_exposure_ratio) : 1.0f;
	const int saturation = camera.saturation_code;
	frame.radiance.create(rgb.size(), CV_32FC3);
	frame.saturated.create(rgb.size(), CV_8UC1);
	parallel_for(cv::Range(0, rgb.rows), [&](const cv::Range &p_rows) {
		for (int y = p_rows.start; y < p_rows.end; y++) {
			const cv::Vec3b *in = rgb.ptr<cv::Vec3b>(y);
			const float *iv = inverse_vignetting.ptr<float>(y);
			cv::Vec3f *o = frame.radiance.ptr<cv::Vec3f>(y);
			uint8_t *s = frame.saturated.ptr<uint8_t>(y);
			for (int x = 0; x < rgb.cols; x++) {
				const float scale = iv[x] * over_exposure;
				for (int c = 0; c < 3; c++) {
					o[x][c] = scaled[size_t(c)][in[x][c]] * scale;
				}
				s[x] = (in[x][0] >= saturation || in[x][1] >= saturation || in[x][2] >= saturation) ? 255 : 0;
			}
		}
	});
	return frame;
}

ResponseCurve rgb_radiance_lut(const RigPhotometry &p_photometry) {
	ResponseCurve lut{};
	for (size_t k = 0; k < 256; k++) {
		lut[k] = p_photometry.known ? float(p_photometry.rgb.response[1][k] * p_photometry.rgb.channel_gains[1]) : float(k) / 255.0f;
	}
	return lut;
}

} // namespace roomprobe
