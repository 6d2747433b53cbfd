#include "rig.h"

#include <io/input_path.h>
#include <io/opencv.h>
#include <io/replace_file.h>
#include <io/yaml_fields.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <sstream>

namespace roomprobe {

namespace {

constexpr const char *RGB_MODEL = "pinhole_radtan";
constexpr const char *FISHEYE_MODEL = "unified_omni";

std::string format_double(double p_value) {
	char buffer[64];
	const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), p_value);
	return std::string(buffer, result.ptr);
}

// ------------------------------------------------------------------------------ value checks

// Collects the first problem, as "field: problem".
struct Checker {
	std::string error;

	void fail(const std::string &p_field, const std::string &p_problem) {
		if (error.empty()) {
			error = p_field + ": " + p_problem;
		}
	}
	void finite(const std::string &p_field, double p_value) {
		if (!std::isfinite(p_value)) {
			fail(p_field, "must be finite (got " + format_double(p_value) + ")");
		}
	}
	void positive(const std::string &p_field, double p_value) {
		if (!(std::isfinite(p_value) && p_value > 0.0)) {
			fail(p_field, "must be positive (got " + format_double(p_value) + ")");
		}
	}
	void positive(const std::string &p_field, int p_value) {
		if (p_value <= 0) {
			fail(p_field, "must be positive (got " + std::to_string(p_value) + ")");
		}
	}
	// An image side: positive and at most RIG_MAX_IMAGE_SIDE pixels (a 100000-pixel side would ask
	// for tens of gigabytes a frame before anything could say what is wrong).
	void image_side(const std::string &p_field, int p_value) {
		positive(p_field, p_value);
		if (p_value > RIG_MAX_IMAGE_SIDE) {
			fail(p_field, "must be at most " + std::to_string(RIG_MAX_IMAGE_SIDE) + " pixels (got " + std::to_string(p_value) + ")");
		}
	}
	// A principal point: on the image (issue #38: one a million pixels off sent every ray of the
	// raycast past the model, the march spinning through empty blocks).
	void on_image(const std::string &p_field, double p_value, int p_side) {
		finite(p_field, p_value);
		if (std::isfinite(p_value) && !(p_value >= 0.0 && p_value <= double(p_side))) {
			fail(p_field, "must lie on the image, in [0, " + std::to_string(p_side) + "] pixels (got " + format_double(p_value) + ")");
		}
	}
	void non_negative(const std::string &p_field, double p_value) {
		if (!(std::isfinite(p_value) && p_value >= 0.0)) {
			fail(p_field, "must be zero or positive (got " + format_double(p_value) + ")");
		}
	}
};

std::string quaternion_problem(const glm::dquat &p_rotation) {
	return "not a unit quaternion (norm " + format_double(glm::length(p_rotation)) + ", allowed 1 +- " +
			format_double(RIG_UNIT_TOLERANCE) + ")";
}

} // namespace

std::string check_rig(const Rig &p_rig) {
	Checker c;
	const PinholeParams &rgb = p_rig.rgb;
	c.image_side("rgb.width", rgb.width);
	c.image_side("rgb.height", rgb.height);
	c.positive("rgb.fx", rgb.fx);
	c.positive("rgb.fy", rgb.fy);
	c.on_image("rgb.cx", rgb.cx, rgb.width);
	c.on_image("rgb.cy", rgb.cy, rgb.height);
	c.finite("rgb.k1", rgb.k1);
	c.finite("rgb.k2", rgb.k2);
	c.finite("rgb.p1", rgb.p1);
	c.finite("rgb.p2", rgb.p2);
	c.finite("rgb.k3", rgb.k3);
	c.positive("depth_scale_m", p_rig.depth_scale_m);
	if (!(p_rig.rgbd_latency_s >= 0.0 && p_rig.rgbd_latency_s <= 1.0)) {
		c.fail("rgbd_latency_s", "must be within 0 to 1 seconds (got " + std::to_string(p_rig.rgbd_latency_s) + ")");
	}

	const std::string photometry_problem = check_photometry(p_rig.photometry);
	if (!photometry_problem.empty()) {
		c.fail(photometry_problem.substr(0, photometry_problem.find(": ")), photometry_problem.substr(photometry_problem.find(": ") + 2));
	}
	if (!p_rig.has_fisheye()) {
		if (p_rig.fisheye_latency_s != 0.0) {
			c.fail("fisheye_latency_s", "must be 0 for a rig without a fisheye");
		}
		if (p_rig.photometry.known) {
			c.fail("photometry", "given for a rig without a fisheye (it describes both cameras)");
		}
		return c.error;
	}
	const OmniParams &fisheye = p_rig.fisheye;
	c.image_side("fisheye.width", fisheye.width);
	c.image_side("fisheye.height", fisheye.height);
	c.non_negative("fisheye.xi", fisheye.xi);
	c.positive("fisheye.fx", fisheye.fx);
	c.positive("fisheye.fy", fisheye.fy);
	c.on_image("fisheye.cx", fisheye.cx, fisheye.width);
	c.on_image("fisheye.cy", fisheye.cy, fisheye.height);
	c.finite("fisheye.skew", fisheye.skew);
	c.finite("fisheye.k1", fisheye.k1);
	c.finite("fisheye.k2", fisheye.k2);
	c.finite("fisheye.p1", fisheye.p1);
	c.finite("fisheye.p2", fisheye.p2);
	c.finite("fisheye.circle_cx", fisheye.circle_cx);
	c.finite("fisheye.circle_cy", fisheye.circle_cy);
	c.non_negative("fisheye.circle_radius", fisheye.circle_radius);
	if (!(std::isfinite(fisheye.max_angle_deg) && fisheye.max_angle_deg >= 0.0 && fisheye.max_angle_deg <= 180.0)) {
		c.fail("fisheye.max_angle_deg", "must be in [0, 180] (got " + format_double(fisheye.max_angle_deg) + ")");
	} else if (fisheye.max_angle_deg > 0.0 && std::isfinite(fisheye.xi) &&
			std::cos(fisheye.max_angle_deg * std::numbers::pi / 180.0) + fisheye.xi <= 0.0) {
		// The unified model divides by cos(angle) + xi: rays beyond acos(-xi) have no pixel.
		const double limit_deg = fisheye.xi >= 1.0 ? 180.0 : std::acos(-fisheye.xi) * 180.0 / std::numbers::pi;
		c.fail("fisheye.max_angle_deg", format_double(fisheye.max_angle_deg) + " is beyond what xi = " +
				format_double(fisheye.xi) + " can project (less than " + format_double(limit_deg) + ")");
	}

	const Pose &extrinsic = p_rig.rgb_from_fisheye;
	const glm::dquat &q = extrinsic.rotation;
	if (!(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w))) {
		c.fail("rgb_from_fisheye.rotation_xyzw", "must be finite");
	} else if (!(std::abs(glm::length(q) - 1.0) <= RIG_UNIT_TOLERANCE)) {
		c.fail("rgb_from_fisheye.rotation_xyzw", quaternion_problem(q));
	}
	c.finite("rgb_from_fisheye.translation_m[0]", extrinsic.translation.x);
	c.finite("rgb_from_fisheye.translation_m[1]", extrinsic.translation.y);
	c.finite("rgb_from_fisheye.translation_m[2]", extrinsic.translation.z);
	c.finite("fisheye_time_offset_s", p_rig.fisheye_time_offset_s);
	if (!(p_rig.fisheye_latency_s >= 0.0 && p_rig.fisheye_latency_s <= 1.0)) {
		c.fail("fisheye_latency_s", "must be within 0 to 1 seconds (got " + std::to_string(p_rig.fisheye_latency_s) + ")");
	}
	return c.error;
}

// ---------------------------------------------------------------------------------- reading

namespace {

bool read_rgb(YamlFieldReader &p_reader, const cv::FileNode &p_root, PinholeParams *r_rgb) {
	cv::FileNode node;
	std::string model;
	const std::string prefix = "rgb.";
	if (!p_reader.map(p_root, "", "rgb", &node) ||
			!p_reader.check_keys(node, prefix, { "model", "width", "height", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3" }) ||
			!p_reader.text(node, prefix, "model", &model)) {
		return false;
	}
	if (model != RGB_MODEL) {
		return p_reader.fail("rgb.model", "'" + model + "' is not a model RoomProbe knows (expected '" + RGB_MODEL + "')");
	}
	return p_reader.integer(node, prefix, "width", &r_rgb->width) && p_reader.integer(node, prefix, "height", &r_rgb->height) &&
			p_reader.real(node, prefix, "fx", &r_rgb->fx) && p_reader.real(node, prefix, "fy", &r_rgb->fy) &&
			p_reader.real(node, prefix, "cx", &r_rgb->cx) && p_reader.real(node, prefix, "cy", &r_rgb->cy) &&
			p_reader.real(node, prefix, "k1", &r_rgb->k1) && p_reader.real(node, prefix, "k2", &r_rgb->k2) &&
			p_reader.real(node, prefix, "p1", &r_rgb->p1) && p_reader.real(node, prefix, "p2", &r_rgb->p2) &&
			p_reader.real(node, prefix, "k3", &r_rgb->k3);
}

bool read_fisheye(YamlFieldReader &p_reader, const cv::FileNode &p_root, OmniParams *r_fisheye) {
	cv::FileNode node;
	std::string model;
	const std::string prefix = "fisheye.";
	if (!p_reader.map(p_root, "", "fisheye", &node) ||
			!p_reader.check_keys(node, prefix,
					{ "model", "width", "height", "xi", "fx", "fy", "cx", "cy", "skew", "k1", "k2", "p1", "p2", "circle_cx",
							"circle_cy", "circle_radius", "max_angle_deg" }) ||
			!p_reader.text(node, prefix, "model", &model)) {
		return false;
	}
	if (model != FISHEYE_MODEL) {
		return p_reader.fail("fisheye.model", "'" + model + "' is not a model RoomProbe knows (expected '" + FISHEYE_MODEL + "')");
	}
	return p_reader.integer(node, prefix, "width", &r_fisheye->width) &&
			p_reader.integer(node, prefix, "height", &r_fisheye->height) && p_reader.real(node, prefix, "xi", &r_fisheye->xi) &&
			p_reader.real(node, prefix, "fx", &r_fisheye->fx) && p_reader.real(node, prefix, "fy", &r_fisheye->fy) &&
			p_reader.real(node, prefix, "cx", &r_fisheye->cx) && p_reader.real(node, prefix, "cy", &r_fisheye->cy) &&
			p_reader.real(node, prefix, "skew", &r_fisheye->skew) && p_reader.real(node, prefix, "k1", &r_fisheye->k1) &&
			p_reader.real(node, prefix, "k2", &r_fisheye->k2) && p_reader.real(node, prefix, "p1", &r_fisheye->p1) &&
			p_reader.real(node, prefix, "p2", &r_fisheye->p2) &&
			p_reader.real(node, prefix, "circle_cx", &r_fisheye->circle_cx) &&
			p_reader.real(node, prefix, "circle_cy", &r_fisheye->circle_cy) &&
			p_reader.real(node, prefix, "circle_radius", &r_fisheye->circle_radius) &&
			p_reader.real(node, prefix, "max_angle_deg", &r_fisheye->max_angle_deg);
}

bool read_extrinsic(YamlFieldReader &p_reader, const cv::FileNode &p_root, Pose *r_rgb_from_fisheye) {
	cv::FileNode node;
	const std::string prefix = "rgb_from_fisheye.";
	double q[4];
	double t[3];
	if (!p_reader.map(p_root, "", "rgb_from_fisheye", &node) ||
			!p_reader.check_keys(node, prefix, { "rotation_xyzw", "translation_m" }) ||
			!p_reader.reals(node, prefix, "rotation_xyzw", 4, q) || !p_reader.reals(node, prefix, "translation_m", 3, t)) {
		return false;
	}
	glm::dquat rotation(q[3], q[0], q[1], q[2]); // glm's constructor takes (w, x, y, z)
	if (!normalize_rotation(&rotation, RIG_UNIT_TOLERANCE)) {
		return p_reader.fail("rgb_from_fisheye.rotation_xyzw", quaternion_problem(rotation));
	}
	r_rgb_from_fisheye->rotation = rotation;
	r_rgb_from_fisheye->translation = glm::dvec3(t[0], t[1], t[2]);
	return true;
}

bool read_camera_photometry(YamlFieldReader &p_reader, const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, CameraPhotometry *r_camera) {
	cv::FileNode node;
	if (!p_reader.map(p_parent, p_prefix, p_key, &node)) {
		return false;
	}
	const std::string prefix = p_prefix + p_key + ".";
	if (!p_reader.check_keys(node, prefix,
				{ "response_r", "response_g", "response_b", "vignetting", "channel_gains", "reference_exposure_us", "reference_gain_db", "saturation_code" },
				{ "response_r", "response_g", "response_b", "channel_gains", "saturation_code" })) {
		return false;
	}
	const char *responses[3] = { "response_r", "response_g", "response_b" };
	for (int c = 0; c < 3; c++) {
		double values[256];
		if (!p_reader.reals(node, prefix, responses[c], 256, values)) {
			return false;
		}
		for (size_t k = 0; k < 256; k++) {
			r_camera->response[size_t(c)][k] = float(values[k]);
		}
	}
	double gains[3];
	if (!p_reader.reals(node, prefix, "channel_gains", 3, gains) || !p_reader.integer(node, prefix, "saturation_code", &r_camera->saturation_code)) {
		return false;
	}
	r_camera->channel_gains = glm::dvec3(gains[0], gains[1], gains[2]);
	r_camera->vignetting.clear();
	const cv::FileNode vignetting = node["vignetting"];
	if (!vignetting.empty()) {
		if (!vignetting.isSeq() || vignetting.size() > 4096) {
			return p_reader.fail(prefix + "vignetting", "must be a list of at most 4096 numbers");
		}
		std::vector<double> values(vignetting.size());
		if (!p_reader.numbers(vignetting, prefix + "vignetting", values.size(), values.data())) {
			return false;
		}
		r_camera->vignetting.assign(values.begin(), values.end());
	}
	r_camera->reference_exposure_us = std::numeric_limits<double>::quiet_NaN();
	r_camera->reference_gain_db = 0.0;
	return (node["reference_exposure_us"].empty() || p_reader.real(node, prefix, "reference_exposure_us", &r_camera->reference_exposure_us)) &&
			(node["reference_gain_db"].empty() || p_reader.real(node, prefix, "reference_gain_db", &r_camera->reference_gain_db));
}

bool read_photometry(YamlFieldReader &p_reader, const cv::FileNode &p_root, RigPhotometry *r_photometry) {
	*r_photometry = RigPhotometry();
	if (p_root["photometry"].empty()) {
		return true;
	}
	cv::FileNode node;
	if (!p_reader.map(p_root, "", "photometry", &node) || !p_reader.check_keys(node, "photometry.", { "radiance_unit", "fisheye", "rgb" }, { "fisheye", "rgb" }) ||
			!read_camera_photometry(p_reader, node, "photometry.", "fisheye", &r_photometry->fisheye) ||
			!read_camera_photometry(p_reader, node, "photometry.", "rgb", &r_photometry->rgb)) {
		return false;
	}
	r_photometry->known = true;
	return true;
}

bool read_rig(YamlFieldReader &p_reader, const cv::FileNode &p_root, Rig *r_rig) {
	if (!p_root.isMap()) {
		return p_reader.fail("roomprobe_rig", "missing (the file is not a map of fields; is it a RoomProbe rig file?)");
	}
	int version = 0;
	const cv::FileNode version_node = p_root["roomprobe_rig"];
	if (version_node.empty() || version_node.isNone()) {
		return p_reader.fail("roomprobe_rig", "missing (is this a RoomProbe rig file?)");
	}
	if (!p_reader.integer(p_root, "", "roomprobe_rig", &version)) {
		return false;
	}
	if (version != 1 && version != RIG_FILE_VERSION) {
		return p_reader.fail("roomprobe_rig", "unknown version " + std::to_string(version) + " (this build reads versions 1 and " +
						std::to_string(RIG_FILE_VERSION) + ")");
	}
	if (version == 1 && !p_root["photometry"].empty()) {
		return p_reader.fail("photometry", "needs roomprobe_rig: 2 (version 1 files have no photometry)");
	}
	if (!p_reader.check_keys(p_root, "",
				{ "roomprobe_rig", "rgb", "depth_scale_m", "fisheye", "rgb_from_fisheye", "fisheye_time_offset_s", "rgbd_latency_s", "fisheye_latency_s",
						"photometry", "calibration_report" },
				{ "roomprobe_rig", "rgb", "depth_scale_m" }) ||
			!read_rgb(p_reader, p_root, &r_rig->rgb) || !p_reader.real(p_root, "", "depth_scale_m", &r_rig->depth_scale_m) ||
			!read_photometry(p_reader, p_root, &r_rig->photometry)) {
		return false;
	}
	// The live capture's latencies are optional (files from before them, synthetic rigs).
	r_rig->rgbd_latency_s = 0.0;
	r_rig->fisheye_latency_s = 0.0;
	if (!p_root["rgbd_latency_s"].empty() && !p_reader.real(p_root, "", "rgbd_latency_s", &r_rig->rgbd_latency_s)) {
		return false;
	}
	if (!p_root["fisheye_latency_s"].empty()) {
		if (p_root["fisheye"].empty()) {
			return p_reader.fail("fisheye_latency_s", "given for a rig without a fisheye");
		}
		if (!p_reader.real(p_root, "", "fisheye_latency_s", &r_rig->fisheye_latency_s)) {
			return false;
		}
	}
	// An RGB-D camera alone leaves out all three fisheye fields; one of them alone is a mistake.
	const char *fisheye_fields[3] = { "fisheye", "rgb_from_fisheye", "fisheye_time_offset_s" };
	int present = 0;
	for (const char *field : fisheye_fields) {
		const cv::FileNode node = p_root[field];
		present += node.empty() || node.isNone() ? 0 : 1;
	}
	if (present == 0) {
		r_rig->fisheye = OmniParams();
		r_rig->rgb_from_fisheye = Pose();
		r_rig->fisheye_time_offset_s = 0.0;
		return true;
	}
	return read_fisheye(p_reader, p_root, &r_rig->fisheye) && read_extrinsic(p_reader, p_root, &r_rig->rgb_from_fisheye) &&
			p_reader.real(p_root, "", "fisheye_time_offset_s", &r_rig->fisheye_time_offset_s);
}

} // namespace

Rig rgbd_camera_alone(const Rig &p_rig) {
	Rig alone = p_rig;
	alone.fisheye = OmniParams();
	alone.rgb_from_fisheye = Pose();
	alone.fisheye_time_offset_s = 0.0;
	alone.fisheye_latency_s = 0.0;
	alone.photometry = RigPhotometry();
	return alone;
}

RigLoadResult load_rig(const std::string &p_path) {
	RigLoadResult result;
	// Read here, parsed from memory: the errors are ours to word, and OpenCV logs nothing.
	result.error = input_file_problem(p_path, "no such rig file");
	if (!result.error.empty()) {
		return result;
	}
	std::ifstream file(p_path, std::ios::binary);
	std::stringstream buffer;
	buffer << file.rdbuf();
	if (!file) {
		result.error = p_path + ": cannot read the rig file";
		return result;
	}
	const std::string text = buffer.str();
	if (text.empty()) {
		result.error = p_path + ": the rig file is empty";
		return result;
	}
	const std::string malformed = check_yaml_text(text);
	if (!malformed.empty()) {
		result.error = p_path + ": " + malformed;
		return result;
	}
	Rig rig;
	YamlFieldReader reader(YamlFieldReader::NonFinite::Accept); // check_rig words the ranges
	try {
		cv::FileStorage storage(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
		if (!storage.isOpened()) {
			result.error = p_path + ": malformed YAML";
			return result;
		}
		if (!read_rig(reader, storage.root(), &rig)) {
			result.error = p_path + ": " + reader.error;
			return result;
		}
	} catch (const cv::Exception &e) {
		result.error = p_path + ": malformed YAML: " + describe_yaml_parse_error(e);
		return result;
	} catch (const std::exception &e) {
		// OpenCV's parser throws std::length_error on some inputs (e.g. a key that starts with ':').
		result.error = p_path + ": malformed YAML (" + e.what() + ")";
		return result;
	}
	const std::string problem = check_rig(rig);
	if (!problem.empty()) {
		result.error = p_path + ": " + problem;
		return result;
	}
	result.rig = rig;
	result.ok = true;
	return result;
}

// ---------------------------------------------------------------------------------- writing

namespace {

// Whole or not at all: a rig file half written would pass for a rig (io/replace_file.h).
std::string write_text(const std::string &p_path, const std::string &p_text) {
	return replace_file(p_path, p_text.data(), p_text.size());
}

} // namespace

namespace {

void write_report(cv::FileStorage &p_storage, const RigCalibrationReport &p_report, bool p_has_fisheye) {
	p_storage.writeComment("How well the calibration fits its views (./roomprobe calibrate): RMS reprojection errors in pixels,\n"
						   "*_std one standard deviation. RoomProbe does not read it back.");
	p_storage << "calibration_report" << "{";
	p_storage << "board" << p_report.board;
	p_storage << "rgb_views" << int(p_report.rgb_views) << "rgb_rms_px" << p_report.rgb_rms_px;
	const PinholeParams &r = p_report.rgb_std;
	p_storage << "rgb_std" << "{" << "fx" << r.fx << "fy" << r.fy << "cx" << r.cx << "cy" << r.cy << "k1" << r.k1 << "k2" << r.k2 << "p1" << r.p1 << "p2" << r.p2
			  << "}";
	if (p_has_fisheye) {
		p_storage << "fisheye_method" << p_report.fisheye_method;
		p_storage << "fisheye_views" << int(p_report.fisheye_views) << "fisheye_rms_px" << p_report.fisheye_rms_px;
		const OmniParams &f = p_report.fisheye_std;
		p_storage << "fisheye_std" << "{" << "xi" << f.xi << "fx" << f.fx << "fy" << f.fy << "cx" << f.cx << "cy" << f.cy << "k1" << f.k1 << "k2" << f.k2 << "p1"
				  << f.p1 << "p2" << f.p2 << "}";
		p_storage << "pair_views" << int(p_report.pair_views) << "pair_rgb_rms_px" << p_report.pair_rgb_rms_px << "pair_fisheye_rms_px"
				  << p_report.pair_fisheye_rms_px;
		const glm::dvec3 &t = p_report.rgb_from_fisheye_translation_std_m;
		const glm::dvec3 &a = p_report.rgb_from_fisheye_rotation_std_deg;
		p_storage << "rgb_from_fisheye_translation_std_m" << "[:" << t.x << t.y << t.z << "]";
		p_storage << "rgb_from_fisheye_rotation_std_deg" << "[:" << a.x << a.y << a.z << "]";
		p_storage << "clock_offset" << p_report.clock_offset;
		if (!p_report.photometry.empty()) {
			p_storage << "photometry" << "{" << "method" << p_report.photometry << "response_fit_rms_ln" << p_report.response_fit_rms << "vignetting_fit_rms"
					  << p_report.vignetting_fit_rms << "colour_fit_rms" << p_report.colour_fit_rms << "}";
		}
	}
	if (p_report.depth_checked) {
		p_storage << "depth" << "{" << "scale" << p_report.depth_scale << "offset_m" << p_report.depth_offset_m << "residual_rms_m" << p_report.depth_residual_rms_m
				  << "raw_rms_m" << p_report.depth_raw_rms_m << "samples" << int(p_report.depth_samples) << "}";
	}
	p_storage << "}";
}

void write_camera_photometry(cv::FileStorage &p_storage, const char *p_key, const CameraPhotometry &p_camera) {
	p_storage << p_key << "{";
	const char *responses[3] = { "response_r", "response_g", "response_b" };
	for (int c = 0; c < 3; c++) {
		p_storage << responses[c] << "[:";
		for (float v : p_camera.response[size_t(c)]) {
			p_storage << v;
		}
		p_storage << "]";
	}
	if (!p_camera.vignetting.empty()) {
		p_storage << "vignetting" << "[:";
		for (float v : p_camera.vignetting) {
			p_storage << v;
		}
		p_storage << "]";
	}
	const glm::dvec3 &g = p_camera.channel_gains;
	p_storage << "channel_gains" << "[:" << g.x << g.y << g.z << "]";
	if (std::isfinite(p_camera.reference_exposure_us)) {
		p_storage << "reference_exposure_us" << p_camera.reference_exposure_us << "reference_gain_db" << p_camera.reference_gain_db;
	}
	p_storage << "saturation_code" << p_camera.saturation_code;
	p_storage << "}";
}

void write_photometry(cv::FileStorage &p_storage, const RigPhotometry &p_photometry) {
	p_storage.writeComment("Photometry (rig/photometry.h): radiance_c = channel_gains_c * response_c[code] / exposure ratio / vignetting(r).\n"
						   "response: linear value of each 8-bit code; vignetting: gain at radius i / (n - 1) of the image circle.");
	p_storage << "photometry" << "{";
	p_storage << "radiance_unit" << "linear value of the RGB camera at its exposure";
	write_camera_photometry(p_storage, "fisheye", p_photometry.fisheye);
	write_camera_photometry(p_storage, "rgb", p_photometry.rgb);
	p_storage << "}";
}

} // namespace

std::string save_rig(const std::string &p_path, const Rig &p_rig, const RigCalibrationReport *p_report) {
	// Never write a file that load_rig would refuse.
	const std::string problem = check_rig(p_rig);
	if (!problem.empty()) {
		return p_path + ": " + problem;
	}
	const glm::dquat q = glm::normalize(p_rig.rgb_from_fisheye.rotation);
	const glm::dvec3 &t = p_rig.rgb_from_fisheye.translation;
	const PinholeParams &rgb = p_rig.rgb;
	const OmniParams &fisheye = p_rig.fisheye;
	std::string text;
	try {
		// Built in memory, YAML whatever the file's extension, and written below: OpenCV logs
		// nothing and the errors are ours to word.
		cv::FileStorage storage(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
		storage.writeComment("RoomProbe rig calibration; the fields are described in calib/README.md.");
		storage << "roomprobe_rig" << RIG_FILE_VERSION;
		storage.writeComment("RGB-D camera (depth registered to it): pixels; distortion as cv::projectPoints.");
		storage << "rgb" << "{";
		storage << "model" << RGB_MODEL << "width" << rgb.width << "height" << rgb.height;
		storage << "fx" << rgb.fx << "fy" << rgb.fy << "cx" << rgb.cx << "cy" << rgb.cy;
		storage << "k1" << rgb.k1 << "k2" << rgb.k2 << "p1" << rgb.p1 << "p2" << rgb.p2 << "k3" << rgb.k3;
		storage << "}";
		storage << "depth_scale_m" << p_rig.depth_scale_m;
		if (p_rig.rgbd_latency_s != 0.0) {
			storage.writeComment("Live capture: seconds from the RGB-D camera taking a frame to its arrival.");
			storage << "rgbd_latency_s" << p_rig.rgbd_latency_s;
		}
		if (!p_rig.has_fisheye()) {
			storage.writeComment("An RGB-D camera alone: no fisheye, so no extrinsic and no clock offset either.");
			if (p_report) {
				write_report(storage, *p_report, false);
			}
			text = storage.releaseAndGetString();
			return write_text(p_path, text);
		}
		storage.writeComment("Fisheye, unified omnidirectional model (cv::omnidir): pixels, xi unitless, degrees.");
		storage << "fisheye" << "{";
		storage << "model" << FISHEYE_MODEL << "width" << fisheye.width << "height" << fisheye.height;
		storage << "xi" << fisheye.xi << "fx" << fisheye.fx << "fy" << fisheye.fy << "cx" << fisheye.cx << "cy" << fisheye.cy;
		storage << "skew" << fisheye.skew << "k1" << fisheye.k1 << "k2" << fisheye.k2 << "p1" << fisheye.p1 << "p2" << fisheye.p2;
		storage << "circle_cx" << fisheye.circle_cx << "circle_cy" << fisheye.circle_cy;
		storage << "circle_radius" << fisheye.circle_radius << "max_angle_deg" << fisheye.max_angle_deg;
		storage << "}";
		storage.writeComment("x_rgb = R * x_fisheye + t, both frames OpenCV's (x right, y down, z forward); metres.");
		storage << "rgb_from_fisheye" << "{";
		storage << "rotation_xyzw" << "[:" << q.x << q.y << q.z << q.w << "]";
		storage << "translation_m" << "[:" << t.x << t.y << t.z << "]";
		storage << "}";
		storage.writeComment("Seconds to add to a fisheye timestamp to get RGB-D clock time.");
		storage << "fisheye_time_offset_s" << p_rig.fisheye_time_offset_s;
		if (p_rig.fisheye_latency_s != 0.0) {
			storage.writeComment("Live capture: seconds from the fisheye taking a frame to its arrival.");
			storage << "fisheye_latency_s" << p_rig.fisheye_latency_s;
		}
		if (p_rig.photometry.known) {
			write_photometry(storage, p_rig.photometry);
		}
		if (p_report) {
			write_report(storage, *p_report, true);
		}
		text = storage.releaseAndGetString();
	} catch (const cv::Exception &e) {
		return p_path + ": cannot write the rig file: " + e.err;
	} catch (const std::exception &e) {
		return p_path + ": cannot write the rig file: " + e.what();
	}
	return write_text(p_path, text);
}

} // namespace roomprobe
