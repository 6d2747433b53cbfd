// The rig calibration file (rig/rig.h, calib/README.md): calib/synthetic_rig.yaml's values (a
// version 1 file), the save/load round trip (version 2, with photometry), and an error naming the
// file and the field for each bad file.

#include "calibration/photometric_calibration.h"
#include "eval/truth_scene.h"
#include "io/yaml_fields.h"
#include "rig/photometry.h"
#include "rig/rig.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// The repository's calib/ from this source file's path (relative to the build's directory, the
// repository root, where the test runner also runs the tests).
std::string synthetic_rig_path() {
	return (fs::path(__FILE__).parent_path().parent_path().parent_path() / "calib" / "synthetic_rig.yaml").string();
}

std::string read_text(const std::string &p_path) {
	std::ifstream file(p_path);
	std::stringstream text;
	text << file.rdbuf();
	return text.str();
}

// Replaces the one occurrence of p_old.
std::string replace_once(std::string p_text, const std::string &p_old, const std::string &p_new) {
	const size_t at = p_text.find(p_old);
	REQUIRE_MESSAGE(at != std::string::npos, p_old);
	REQUIRE_MESSAGE(p_text.find(p_old, at + 1) == std::string::npos, p_old);
	return p_text.replace(at, p_old.size(), p_new);
}

// Replaces the text from p_begin up to (not including) p_end.
std::string replace_block(std::string p_text, const std::string &p_begin, const std::string &p_end, const std::string &p_new) {
	const size_t begin = p_text.find(p_begin);
	REQUIRE_MESSAGE(begin != std::string::npos, p_begin);
	const size_t end = p_text.find(p_end, begin);
	REQUIRE_MESSAGE(end != std::string::npos, p_end);
	return p_text.replace(begin, end - begin, p_new);
}

struct TempDir {
	fs::path path;
	explicit TempDir(const std::string &p_name) :
			path(fs::temp_directory_path() / ("roomprobe_" + std::to_string(getpid()) + "_" + p_name)) {
		fs::create_directories(path);
	}
	~TempDir() {
		std::error_code ec;
		fs::remove_all(path, ec);
	}
	std::string write(const std::string &p_name, const std::string &p_text) const {
		const fs::path file = path / p_name;
		std::ofstream(file) << p_text;
		return file.string();
	}
};

void check_same_rig(const Rig &p_a, const Rig &p_b) {
	CHECK(p_a.rgb.width == p_b.rgb.width);
	CHECK(p_a.rgb.height == p_b.rgb.height);
	CHECK(p_a.rgb.fx == p_b.rgb.fx);
	CHECK(p_a.rgb.fy == p_b.rgb.fy);
	CHECK(p_a.rgb.cx == p_b.rgb.cx);
	CHECK(p_a.rgb.cy == p_b.rgb.cy);
	CHECK(p_a.rgb.k1 == p_b.rgb.k1);
	CHECK(p_a.rgb.k2 == p_b.rgb.k2);
	CHECK(p_a.rgb.p1 == p_b.rgb.p1);
	CHECK(p_a.rgb.p2 == p_b.rgb.p2);
	CHECK(p_a.rgb.k3 == p_b.rgb.k3);
	CHECK(p_a.depth_scale_m == p_b.depth_scale_m);
	const OmniParams &f = p_a.fisheye;
	const OmniParams &g = p_b.fisheye;
	CHECK(f.width == g.width);
	CHECK(f.height == g.height);
	CHECK(f.xi == g.xi);
	CHECK(f.fx == g.fx);
	CHECK(f.fy == g.fy);
	CHECK(f.cx == g.cx);
	CHECK(f.cy == g.cy);
	CHECK(f.skew == g.skew);
	CHECK(f.k1 == g.k1);
	CHECK(f.k2 == g.k2);
	CHECK(f.p1 == g.p1);
	CHECK(f.p2 == g.p2);
	CHECK(f.circle_cx == g.circle_cx);
	CHECK(f.circle_cy == g.circle_cy);
	CHECK(f.circle_radius == g.circle_radius);
	CHECK(f.max_angle_deg == g.max_angle_deg);
	CHECK(glm::length(p_a.rgb_from_fisheye.rotation - p_b.rgb_from_fisheye.rotation) < 1e-15);
	CHECK(p_a.rgb_from_fisheye.translation == p_b.rgb_from_fisheye.translation);
	CHECK(p_a.fisheye_time_offset_s == p_b.fisheye_time_offset_s);
}

} // namespace

TEST_CASE("rig file: calib/synthetic_rig.yaml has the synthetic recordings' rig") {
	const RigLoadResult loaded = load_rig(synthetic_rig_path());
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	const Rig &rig = loaded.rig;
	CHECK(rig.rgb.width == 640);
	CHECK(rig.rgb.height == 480);
	CHECK(rig.rgb.fx == 525.0);
	CHECK(rig.rgb.fy == 525.0);
	CHECK(rig.rgb.cx == 319.5);
	CHECK(rig.rgb.cy == 239.5);
	CHECK((rig.rgb.k1 == 0.0 && rig.rgb.k2 == 0.0 && rig.rgb.p1 == 0.0 && rig.rgb.p2 == 0.0 && rig.rgb.k3 == 0.0));
	CHECK(rig.depth_scale_m == 0.001);

	const OmniParams &fisheye = rig.fisheye;
	CHECK(fisheye.width == 1024);
	CHECK(fisheye.height == 1024);
	CHECK(fisheye.xi == 1.0);
	CHECK(fisheye.fx == fisheye.fy);
	CHECK((fisheye.cx == 511.5 && fisheye.cy == 511.5 && fisheye.circle_cx == 511.5 && fisheye.circle_cy == 511.5));
	CHECK(fisheye.circle_radius == 500.0);
	CHECK(fisheye.max_angle_deg == 92.5);
	CHECK((fisheye.skew == 0.0 && fisheye.k1 == 0.0 && fisheye.k2 == 0.0 && fisheye.p1 == 0.0 && fisheye.p2 == 0.0));
	// The ray at the edge of the 185-degree field lands on the image circle: r = f sin t / (cos t + xi).
	const double theta = fisheye.max_angle_deg * std::numbers::pi / 180.0;
	CHECK(std::abs(fisheye.fx * std::sin(theta) / (std::cos(theta) + fisheye.xi) - fisheye.circle_radius) < 1e-9);

	// The fisheye looks up (the RGB camera's -y), its image x along the RGB camera's x, and sits
	// 8 cm above and 2 cm ahead of it.
	const Pose &extrinsic = rig.rgb_from_fisheye;
	CHECK(glm::length(extrinsic.rotation * glm::dvec3(0, 0, 1) - glm::dvec3(0, -1, 0)) < 1e-15);
	CHECK(glm::length(extrinsic.rotation * glm::dvec3(1, 0, 0) - glm::dvec3(1, 0, 0)) < 1e-15);
	CHECK(glm::length(extrinsic.rotation * glm::dvec3(0, 1, 0) - glm::dvec3(0, 0, 1)) < 1e-15);
	CHECK(extrinsic.translation == glm::dvec3(0.0, -0.08, 0.02));
	CHECK(rig.fisheye_time_offset_s == 0.0137);
	CHECK(check_rig(rig) == "");
}

TEST_CASE("rig file: save then load gives the same rig") {
	TempDir dir("rig_roundtrip");
	const RigLoadResult synthetic = load_rig(synthetic_rig_path());
	REQUIRE_MESSAGE(synthetic.ok, synthetic.error);
	const std::string path = (dir.path / "synthetic_copy.yaml").string();
	REQUIRE(save_rig(path, synthetic.rig) == "");
	const RigLoadResult again = load_rig(path);
	REQUIRE_MESSAGE(again.ok, again.error);
	check_same_rig(again.rig, synthetic.rig);

	// Every field distinct and not round in decimal, so a swapped or truncated field shows.
	Rig rig;
	rig.rgb = { 1280, 720, 911.123456789012, 910.987654321098, 641.3, 359.7, 0.1234, -0.0567, 1.2e-4, -3.4e-5, 0.00789 };
	rig.depth_scale_m = 1.0 / 3000.0;
	rig.fisheye = { 1280, 960, 1.0712345678, 345.6789, 344.321, 640.25, 479.75, 0.0123,
		-0.011, 0.0022, 1e-5, -2e-5, 641.0, 480.5, 455.5, 95.0 };
	rig.rgb_from_fisheye.rotation = glm::normalize(glm::dquat(0.71, 0.69, -0.05, 0.1));
	rig.rgb_from_fisheye.translation = glm::dvec3(0.0031, -0.0812345, 0.0199);
	rig.fisheye_time_offset_s = -0.004321;
	const std::string other = (dir.path / "other.rig").string(); // not .yaml: still YAML
	REQUIRE(save_rig(other, rig) == "");
	CHECK(read_text(other).rfind("%YAML:1.0", 0) == 0);
	const RigLoadResult other_again = load_rig(other);
	REQUIRE_MESSAGE(other_again.ok, other_again.error);
	check_same_rig(other_again.rig, rig);
}

TEST_CASE("rig file: each bad file gives an error naming the file and the field") {
	TempDir dir("rig_bad");
	const std::string good = read_text(synthetic_rig_path());
	REQUIRE(contains(good, "roomprobe_rig: 1"));

	struct Case {
		const char *name;
		std::string text;
		const char *field; // expected in the error, after the file's path
		const char *hint;
	};
	const Case cases[] = {
		{ "missing_xi", replace_once(good, "  xi: 1.0\n", ""), "fisheye.xi", "missing" },
		{ "wrong_fisheye_model", replace_once(good, "model: unified_omni", "model: kannala_brandt"), "fisheye.model", "kannala_brandt" },
		{ "wrong_rgb_model", replace_once(good, "model: pinhole_radtan", "model: pinhole"), "rgb.model", "pinhole_radtan" },
		{ "negative_fx", replace_once(good, "  fx: 525.0", "  fx: -525.0"), "rgb.fx", "must be positive" },
		// Issue #38: a principal point far off the image sent the raycast spinning.
		{ "principal_point_off_the_image", replace_once(good, "  cx: 319.5", "  cx: 1000000.0"), "rgb.cx", "must lie on the image, in [0, 640] pixels" },
		{ "fisheye_principal_point_negative", replace_once(good, "  cx: 511.5", "  cx: -3.0"), "fisheye.cx", "must lie on the image, in [0, 1024] pixels" },
		{ "zero_fisheye_fy", replace_once(good, "  fy: 478.645871127404", "  fy: 0"), "fisheye.fy", "must be positive" },
		{ "zero_width", replace_once(good, "  width: 640", "  width: 0"), "rgb.width", "must be positive" },
		{ "fractional_height", replace_once(good, "  height: 1024", "  height: 1024.5"), "fisheye.height", "integer" },
		// A fisheye of 100000 x 100000 once made OpenCV fail to allocate 40 GB in the evaluation.
		{ "huge_fisheye", replace_once(replace_once(good, "  width: 1024", "  width: 100000"), "  height: 1024", "  height: 100000"), "fisheye.width",
				"at most 16384 pixels" },
		{ "huge_rgb_height", replace_once(good, "  height: 480", "  height: 20000"), "rgb.height", "at most 16384 pixels" },
		{ "bad_quaternion", replace_once(good, "[0.7071067811865476, 0.0, 0.0, 0.7071067811865476]", "[0.5, 0.0, 0.0, 0.5]"),
				"rgb_from_fisheye.rotation_xyzw", "unit quaternion" },
		{ "short_quaternion", replace_once(good, "[0.7071067811865476, 0.0, 0.0, 0.7071067811865476]", "[0.0, 0.0, 1.0]"),
				"rgb_from_fisheye.rotation_xyzw", "4 numbers" },
		{ "text_translation", replace_once(good, "[0.0, -0.08, 0.02]", "[0.0, up, 0.02]"), "rgb_from_fisheye.translation_m[1]", "number" },
		{ "unknown_version", replace_once(good, "roomprobe_rig: 1", "roomprobe_rig: 3"), "roomprobe_rig", "unknown version 3" },
		{ "no_version", replace_once(good, "roomprobe_rig: 1\n", ""), "roomprobe_rig", "missing" },
		{ "misspelt_field", replace_once(good, "circle_radius:", "circle_radious:"), "fisheye.circle_radious", "unknown field" },
		{ "missing_offset", replace_once(good, "fisheye_time_offset_s: 0.0137\n", ""), "fisheye_time_offset_s", "missing" },
		{ "nan_cx", replace_once(good, "  cx: 319.5", "  cx: .nan"), "rgb.cx", "finite" },
		{ "negative_depth_scale", replace_once(good, "depth_scale_m: 0.001", "depth_scale_m: -0.001"), "depth_scale_m", "positive" },
		{ "angle_beyond_xi", replace_once(good, "  xi: 1.0", "  xi: 0.0"), "fisheye.max_angle_deg", "xi = 0 can project" },
		{ "angle_over_180", replace_once(good, "max_angle_deg: 92.5", "max_angle_deg: 200"), "fisheye.max_angle_deg", "[0, 180]" },
		{ "rgb_not_a_map", replace_block(good, "\nrgb:\n", "\n# 16-bit", "\nrgb: [640, 480]\n"), "rgb", "map" },
	};
	for (const Case &c : cases) {
		const std::string case_name = c.name;
		CAPTURE(case_name);
		const std::string path = dir.write(std::string(c.name) + ".yaml", c.text);
		const RigLoadResult loaded = load_rig(path);
		CHECK_FALSE(loaded.ok);
		CAPTURE(loaded.error);
		CHECK(contains(loaded.error, path + ": " + c.field + ":"));
		CHECK(contains(loaded.error, c.hint));
	}

	// A rotation off unit norm by less than 1e-6 is normalised, not refused.
	const std::string nearly = dir.write("nearly_unit.yaml",
			replace_once(good, "[0.7071067811865476, 0.0, 0.0, 0.7071067811865476]", "[0.70710712, 0.0, 0.0, 0.70710712]"));
	const RigLoadResult normalised = load_rig(nearly);
	REQUIRE_MESSAGE(normalised.ok, normalised.error);
	CHECK(std::abs(glm::length(normalised.rig.rgb_from_fisheye.rotation) - 1.0) < 1e-15);
}

TEST_CASE("rig file: missing, empty and malformed files give an error naming the file") {
	TempDir dir("rig_malformed");
	const std::string good = read_text(synthetic_rig_path());

	const std::string missing = (dir.path / "no_such_rig.yaml").string();
	const RigLoadResult not_there = load_rig(missing);
	CHECK_FALSE(not_there.ok);
	CHECK(contains(not_there.error, missing + ": "));
	CHECK(contains(not_there.error, "no such rig file"));

	const RigLoadResult directory = load_rig(dir.path.string());
	CHECK_FALSE(directory.ok);
	CHECK(contains(directory.error, dir.path.string() + ": "));

	struct Case {
		const char *name;
		std::string text;
		const char *hint;
	};
	const Case cases[] = {
		{ "empty", "", "empty" },
		{ "no_header", replace_once(good, "%YAML:1.0\n", ""), "%YAML:1.0" },
		{ "bad_indentation", replace_once(good, "  width: 640\n", "      width: 640\n"), "malformed YAML: line" },
		{ "unclosed_list", replace_once(good, "[0.0, -0.08, 0.02]", "[0.0, -0.08, 0.02"), "malformed YAML" },
		{ "only_text", "%YAML:1.0\n---\njust some words\n", "malformed YAML" },
		{ "a_list", "%YAML:1.0\n---\n- 1\n- 2\n", "roomprobe_rig" },
		{ "only_header", "%YAML:1.0\n---\n", "roomprobe_rig" },
		{ "binary", std::string("%YAML:1.0\n---\n\x01\x02\xff\xfe: [\x7f\n", 20), "" },
		// Found by fuzzing (./roomprobe fuzz rig): OpenCV's YAML parser never returned on it.
		{ "text_after_marker", "%YAML:1.0\n---J a: 1.\nx  - 1\n", "line 2: text after the document marker" },
		// Found by fuzzing too: fields indented under nothing, then a list item at column 0, also
		// never returned; the block layout is now checked before OpenCV parses.
		{ "misaligned_blocks", "%YAML:1.0\n   model: pinhole_radtan\n   width: A\n- #\n- #1641\n", "line 2: the first field is indented" },
		// Found by fuzzing: OpenCV writes a whole double of 2^31 or more as an integer and reads
		// it back as a 32-bit one (fy 525071067811865 came back as -1569026023).
		{ "huge_focal_length", replace_once(good, "  fy: 525.0\n", "  fy: 525071067811865.\n"), "rgb.fy: must be within +-1e9" },
		{ "whole_number_beyond_32_bits", replace_once(good, "  width: 640\n", "  width: 3000000000\n"), "does not fit 32 bits" },
		{ "octal", replace_once(good, "  width: 640\n", "  width: 01200\n"), "starts with 0 (OpenCV would read it as octal or hexadecimal)" },
		{ "hexadecimal", replace_once(good, "  width: 640\n", "  width: 0x100000280\n"), "starts with 0" },
		{ "bad_header", "%YAML:1..:\nroomprobe_rig: 1\n", "line 1: the header must be '%YAML:1.0'" },
		{ "item_among_fields", "%YAML:1.0\n---\nroomprobe_rig: 1\nrgb:\n  model: x\n  - 1\n", "line 6: a list item among fields" },
		{ "outdented_field", "%YAML:1.0\n---\nroomprobe_rig: 1\nrgb:\n    model: x\n  width: 1\n",
				"line 6: this field's indentation (2 spaces) lines up with no block above it" },
	};
	for (const Case &c : cases) {
		const std::string case_name = c.name;
		CAPTURE(case_name);
		const std::string path = dir.write(std::string(c.name) + ".yaml", c.text);
		const RigLoadResult loaded = load_rig(path);
		CHECK_FALSE(loaded.ok);
		CAPTURE(loaded.error);
		CHECK(contains(loaded.error, path + ": "));
		CHECK(contains(loaded.error, c.hint));
	}
}

TEST_CASE("rig file: save_rig refuses an invalid rig or an unwritable path, naming the file") {
	TempDir dir("rig_save");
	const RigLoadResult synthetic = load_rig(synthetic_rig_path());
	REQUIRE_MESSAGE(synthetic.ok, synthetic.error);

	Rig bad = synthetic.rig;
	bad.fisheye.fx = -1.0;
	const std::string path = (dir.path / "bad.yaml").string();
	const std::string error = save_rig(path, bad);
	CHECK(contains(error, path + ": fisheye.fx: must be positive"));
	CHECK_FALSE(fs::exists(path)); // nothing written

	bad = synthetic.rig;
	bad.rgb_from_fisheye.rotation = glm::dquat(2.0, 0.0, 0.0, 0.0);
	CHECK(contains(save_rig(path, bad), path + ": rgb_from_fisheye.rotation_xyzw: not a unit quaternion"));

	const std::string unwritable = (dir.path / "no_such_dir" / "rig.yaml").string();
	CHECK(contains(save_rig(unwritable, synthetic.rig), unwritable + ": "));
}

TEST_CASE("rig file: an RGB-D camera alone (no fisheye) saves and loads; a fisheye field alone is an error") {
	TempDir dir("rig_no_fisheye");
	const RigLoadResult synthetic = load_rig(synthetic_rig_path());
	REQUIRE_MESSAGE(synthetic.ok, synthetic.error);
	Rig rgbd_only;
	rgbd_only.rgb = synthetic.rig.rgb;
	rgbd_only.depth_scale_m = 0.0002;
	CHECK_FALSE(rgbd_only.has_fisheye());
	CHECK(synthetic.rig.has_fisheye());
	CHECK(check_rig(rgbd_only).empty());

	const std::string path = (dir.path / "rgbd_only.yaml").string();
	REQUIRE(save_rig(path, rgbd_only).empty());
	const std::string text = read_text(path);
	CHECK_FALSE(contains(text, "fisheye:"));
	CHECK_FALSE(contains(text, "rgb_from_fisheye"));
	CHECK_FALSE(contains(text, "fisheye_time_offset_s"));
	const RigLoadResult loaded = load_rig(path);
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	CHECK_FALSE(loaded.rig.has_fisheye());
	check_same_rig(loaded.rig, rgbd_only);

	// Half a fisheye: the width set, the height not.
	Rig half = rgbd_only;
	half.fisheye.width = 100;
	CHECK(contains(check_rig(half), "fisheye.height: must be positive"));

	// The synthetic rig less its fisheye fields loads as an RGB-D camera alone; less only some of
	// them, the missing one is named.
	const std::string good = read_text(synthetic_rig_path());
	const std::string without_fisheye = replace_block(good, "\nfisheye:\n", "\n# x_rgb", "\n");
	const std::string without_all = replace_once(replace_block(without_fisheye, "\nrgb_from_fisheye:\n", "\n# The synthetic", "\n"),
			"fisheye_time_offset_s: 0.0137\n", "");
	const RigLoadResult alone = load_rig(dir.write("without_all.yaml", without_all));
	REQUIRE_MESSAGE(alone.ok, alone.error);
	CHECK_FALSE(alone.rig.has_fisheye());
	CHECK(alone.rig.rgb.fx == 525.0);
	const std::string only_fisheye_gone = dir.write("without_fisheye.yaml", without_fisheye);
	const RigLoadResult partial = load_rig(only_fisheye_gone);
	CHECK_FALSE(partial.ok);
	CHECK(contains(partial.error, only_fisheye_gone + ": fisheye: missing"));
}

TEST_CASE("rig file: version 2 keeps the photometry; version 1 files load without one; bad photometry names its field") {
	TempDir dir("rig_photometry");
	const RigLoadResult v1 = load_rig(synthetic_rig_path());
	REQUIRE_MESSAGE(v1.ok, v1.error);
	CHECK_FALSE(v1.rig.photometry.known);
	Rig rig = v1.rig;
	rig.photometry.known = true;
	rig.photometry.fisheye = tone_curve_photometry(ToneCurve::Log, 2.0, glm::dvec3(1.1, 1.0, 0.85));
	rig.photometry.fisheye.vignetting = radial_vignetting_table(0.5);
	rig.photometry.fisheye.reference_exposure_us = 8000.0;
	rig.photometry.fisheye.reference_gain_db = 3.0;
	rig.photometry.rgb = tone_curve_photometry(ToneCurve::Srgb, 1.0);
	const std::string path = (dir.path / "v2.yaml").string();
	REQUIRE(save_rig(path, rig) == "");
	const std::string text = read_text(path);
	CHECK(contains(text, "roomprobe_rig: 2"));
	const RigLoadResult v2 = load_rig(path);
	REQUIRE_MESSAGE(v2.ok, v2.error);
	check_same_rig(v2.rig, rig);
	const CameraPhotometry &f = v2.rig.photometry.fisheye;
	CHECK(v2.rig.photometry.known);
	for (int c = 0; c < 3; c++) {
		for (int k = 0; k < 256; k++) {
			CHECK(f.response[c][k] == doctest::Approx(rig.photometry.fisheye.response[c][k]).epsilon(1e-6));
		}
		CHECK(f.channel_gains[c] == doctest::Approx(rig.photometry.fisheye.channel_gains[c]));
	}
	CHECK(f.vignetting.size() == 33);
	CHECK(f.vignetting.back() == doctest::Approx(0.5).epsilon(1e-6));
	CHECK(f.reference_exposure_us == 8000.0);
	CHECK(f.reference_gain_db == 3.0);
	CHECK(std::isnan(v2.rig.photometry.rgb.reference_exposure_us));

	struct Case {
		const char *name;
		std::string text;
		const char *field;
		const char *hint;
	};
	const Case cases[] = {
		{ "v1_with_photometry", replace_once(text, "roomprobe_rig: 2", "roomprobe_rig: 1"), "photometry", "needs roomprobe_rig: 2" },
		{ "missing_response", replace_block(text, "      response_g:", "      response_b:", ""), "photometry.fisheye.response_g", "missing" },
		{ "saturation_300", replace_once(text, "      saturation_code: 250\n   rgb:", "      saturation_code: 300\n   rgb:"), "photometry.fisheye.saturation_code",
				"1 to 255" },
		{ "negative_gain", replace_block(text, "      channel_gains: [", "]\n      reference_exposure_us", "      channel_gains: [ -1., 1., 1. "),
				"photometry.fisheye.channel_gains[0]", "positive" },
		{ "unknown_field", replace_once(text, "   rgb:\n", "   rgb:\n      gamma: 2.2\n"), "photometry.rgb.gamma", "unknown field" },
	};
	for (const Case &c : cases) {
		const std::string case_name = c.name;
		CAPTURE(case_name);
		const std::string bad = dir.write(std::string(c.name) + ".yaml", c.text);
		const RigLoadResult loaded = load_rig(bad);
		CHECK_FALSE(loaded.ok);
		CAPTURE(loaded.error);
		CHECK(contains(loaded.error, bad + ": " + c.field + ":"));
		CHECK(contains(loaded.error, c.hint));
	}
	// Values no file may hold are refused when saving too.
	Rig falling = rig;
	falling.photometry.fisheye.response[1][100] = falling.photometry.fisheye.response[1][99] * 0.5f;
	CHECK(contains(save_rig((dir.path / "falling.yaml").string(), falling), "photometry.fisheye.response_g[100]: must not be less than the code below it"));
	Rig first = rig;
	first.photometry.fisheye.vignetting[0] = 0.9f;
	CHECK(contains(save_rig((dir.path / "first.yaml").string(), first), "photometry.fisheye.vignetting[0]: must be 1"));
}

// Issue #38 (found by fuzzing synth.yaml): any positive ratio was taken as the recording's truth,
// so an exposure of 1e-310 gave infinite channel gains and an edge gain of 1e-300 a vignetting
// table of zeros. Ratios are held to [1e-6, 1e6] and the result to check_photometry.
TEST_CASE("synth.yaml: photometry ratios outside [1e-6, 1e6] are refused, naming the field") {
	TempDir dir("synth_ratios");
	for (const std::string &field : { std::string("fisheye_exposure: 1e-310"), std::string("fisheye_vignetting_edge_gain: 1e-300"),
				 std::string("rgb_exposure: 1e300"), std::string("fisheye_channel_gains: [ 1, 1e9, 1 ]") }) {
		CAPTURE(field);
		const std::string synth = dir.write("synth.yaml", "%YAML:1.0\n---\n" + field + "\n");
		RigPhotometry photometry;
		std::string error;
		CHECK_FALSE(read_recording_photometry(dir.path.string(), RigPhotometry(), &photometry, &error));
		CHECK(contains(error, synth + ": " + field.substr(0, field.find(':'))));
		CHECK(contains(error, "within [1e-6, 1e6]"));
	}
	dir.write("synth.yaml", "%YAML:1.0\n---\nfisheye_exposure: 0.5\nfisheye_vignetting_edge_gain: 0.8\n");
	RigPhotometry photometry;
	std::string error;
	CHECK(read_recording_photometry(dir.path.string(), RigPhotometry(), &photometry, &error));
	CHECK(error.empty());
}

// Issue #38: the text that hung OpenCV's parser was screened for the rig and room files only; in a
// recording's synth.yaml it hung eval, bench and RigCapture. Every YAML file a user may give now
// opens through open_yaml_file.
TEST_CASE("YAML files: synth.yaml and photometric.yaml go through the same screen, naming the file") {
	TempDir dir("yaml_screen");
	const std::string hang = "%YAML:1.0\n---J a: 1.\nx  - 1\n"; // OpenCV 4.10 never returned on it
	const std::string synth = dir.write("synth.yaml", hang);
	RigPhotometry photometry;
	std::string error;
	CHECK_FALSE(read_recording_photometry(dir.path.string(), RigPhotometry(), &photometry, &error));
	CHECK(contains(error, synth + ": malformed YAML: line 2"));
	const TruthSceneResult truth = load_truth_scene(dir.path.string());
	CHECK(contains(truth.error, synth + ": malformed YAML"));
	const std::string photometric = dir.write("photometric.yaml", hang);
	const PhotometricViews views = load_photometric_views(dir.path.string(), cv::Size(64, 64));
	CHECK(contains(views.error, photometric + ": malformed YAML: line 2"));

	cv::FileStorage storage;
	CHECK(contains(open_yaml_file((dir.path / "none.yaml").string(), &storage), "none.yaml: missing"));
	CHECK(contains(open_yaml_file(dir.path.string(), &storage), ": a folder, not a file"));
	CHECK(open_yaml_file("/dev/zero", &storage) == "/dev/zero: not a regular file (a character device)");
	const std::string good = dir.write("good.yaml", "%YAML:1.0\n---\nsquare_m: 0.025\nlist: [ 1, 2 ]\n");
	CHECK(open_yaml_file(good, &storage) == "");
	CHECK(double(storage["square_m"]) == doctest::Approx(0.025));
	// photometric.yaml's list items are one-line maps: they pass, and malformed ones are named.
	const std::string sweep = dir.write("sweep.yaml", "%YAML:1.0\nexposure_sweep:\n  - { image: exposure/000.png, exposure_us: 100 }\n  - { image: \"b c.png\", gains: [ 1, 2 ] }\n");
	CHECK(open_yaml_file(sweep, &storage) == "");
	CHECK(std::string(storage["exposure_sweep"][1]["image"]) == "b c.png");
	for (const auto &[text, hint] : { std::pair<const char *, const char *>{ "  - { image: a.png, exposure_us: 100\n", "does not close on its line" },
			 { "  - { image a.png }\n", "holds 'key: value' pairs" }, { "  - { a: { b: 1 } }\n", "a map inside" }, { "  - { a: [ 1, 2 }\n", "must close inside it" } }) {
		CAPTURE(text);
		const std::string bad = dir.write("bad.yaml", std::string("%YAML:1.0\nexposure_sweep:\n") + text);
		CHECK(contains(open_yaml_file(bad, &storage), hint));
	}
}
