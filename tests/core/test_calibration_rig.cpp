// Calibrating the rig (calibration/, paper §3.2) from the synthetic rig's checkerboard and
// photometric views, whose truth is known (synth/synth_sequence.h renders them with test_rig() and
// a fisheye whose response, vignetting and white balance are not the RGB camera's), and refusing
// degenerate input with its reason.

#include "calibration/calibration_views.h"
#include "calibration/photometric_calibration.h"
#include "calibration/rig_calibration.h"
#include "recording/recording_writer.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

// The fisheye's photometric truth: a log response, a white balance of its own, vignetting to
// half at the rim.
synth::FisheyeOptions fisheye_truth() {
	synth::FisheyeOptions options;
	options.tone_curve = ToneCurve::Log;
	options.channel_gains = glm::dvec3(1.1, 1.0, 0.85);
	options.vignetting_edge_gain = 0.5;
	return options;
}

// The synthetic rig's views, rendered once for every test here and removed at exit: the boards,
// and the exposure sweep and flat field in two_rooms.
struct RenderedViews {
	fs::path folder;
	std::string error;
	RenderedViews() {
		folder = fs::temp_directory_path() / ("roomprobe_test_calibration_" + std::to_string(::getpid()));
		fs::remove_all(folder);
		const Rig rig = test_rig();
		synth::CalibrationResult written = synth::write_calibration_views(folder.string(), rig, synth::CheckerboardSpec(), 4, fisheye_truth());
		if (written.ok) {
			const synth::SceneResult scene = synth::make_scene("two_rooms", synth::SceneOptions());
			REQUIRE_MESSAGE(scene.ok, scene.error);
			const synth::SynthRenderer renderer(scene.scene);
			const Pose world_from_fisheye = compose(synth::make_handheld_trajectory(scene.scene, 1).world_from_rgb(0.0), rig.rgb_from_fisheye);
			written = synth::write_photometric_views(folder.string(), renderer, rig.fisheye, world_from_fisheye, fisheye_truth());
		}
		error = written.ok ? "" : written.error;
	}
	~RenderedViews() {
		std::error_code ec;
		fs::remove_all(folder, ec);
	}
};

const RenderedViews &rendered_views() {
	static RenderedViews rendered;
	return rendered;
}

const CalibrationViews &synthetic_views() {
	static CalibrationViews views = [] {
		const RenderedViews &rendered = rendered_views();
		REQUIRE_MESSAGE(rendered.error.empty(), rendered.error);
		return load_calibration_views(rendered.folder.string(), CalibrationViewsOptions());
	}();
	return views;
}

double angle_deg(const glm::dquat &p_a, const glm::dquat &p_b) {
	const double d = std::abs(glm::dot(glm::normalize(p_a), glm::normalize(p_b)));
	return 2.0 * std::acos(std::min(1.0, d)) * 180.0 / 3.14159265358979323846;
}

} // namespace

TEST_CASE("calibration: the synthetic rig's views give back its intrinsics, rgb_from_fisheye and depth") {
	const CalibrationViews &views = synthetic_views();
	REQUIRE_MESSAGE(views.error.empty(), views.error);
	const Rig truth = test_rig();
	const synth::CheckerboardSpec spec;
	CHECK(views.board_from_file);
	CHECK(views.board.inner_x == spec.squares_x - 1);
	CHECK(views.board.inner_y == spec.squares_y - 1);
	for (const std::string &missed : views.missed) {
		MESSAGE("not used: " << missed);
	}
	// Every RGB view detects; so does every pair, in both cameras.
	CHECK(views.rgb.size() == synth::pinhole_board_poses(synth::CheckerboardSpec()).size() + synth::pair_board_poses(spec).size());
	CHECK(views.pairs.size() == synth::pair_board_poses(spec).size());
	// The image circle found from the images is the rig's.
	CHECK(std::abs(views.fisheye_circle.cx - truth.fisheye.circle_cx) < 1.0);
	CHECK(std::abs(views.fisheye_circle.cy - truth.fisheye.circle_cy) < 1.0);
	CHECK(std::abs(views.fisheye_circle.radius - truth.fisheye.circle_radius) < 1.5);

	const RigCalibration calibrated = calibrate_rig(views, RigCalibrationOptions());
	REQUIRE_MESSAGE(calibrated.error.empty(), calibrated.error);
	const Rig &rig = calibrated.rig;
	const RigCalibrationReport &report = calibrated.report;
	MESSAGE("RGB: fx " << rig.rgb.fx << " fy " << rig.rgb.fy << " cx " << rig.rgb.cx << " cy " << rig.rgb.cy << ", RMS " << report.rgb_rms_px << " px over "
					   << report.rgb_views << " views");
	MESSAGE("fisheye: xi " << rig.fisheye.xi << " fx " << rig.fisheye.fx << " fy " << rig.fisheye.fy << " cx " << rig.fisheye.cx << " cy "
						   << rig.fisheye.cy << ", RMS " << report.fisheye_rms_px << " px over " << report.fisheye_views << " views");
	// The bounds: focal lengths within 0.3 %, principal points within 1 px.
	CHECK(std::abs(rig.rgb.fx / truth.rgb.fx - 1.0) < 0.003);
	CHECK(std::abs(rig.rgb.fy / truth.rgb.fy - 1.0) < 0.003);
	CHECK(std::abs(rig.rgb.cx - truth.rgb.cx) < 1.0);
	CHECK(std::abs(rig.rgb.cy - truth.rgb.cy) < 1.0);
	// The unified model's focal length trades against xi; its projection is what must agree: the
	// generalised focal over (1 + xi), the image scale at the axis, within 0.3 %.
	CHECK(std::abs(rig.fisheye.fx / (1.0 + rig.fisheye.xi) / (truth.fisheye.fx / (1.0 + truth.fisheye.xi)) - 1.0) < 0.003);
	CHECK(std::abs(rig.fisheye.fy / (1.0 + rig.fisheye.xi) / (truth.fisheye.fy / (1.0 + truth.fisheye.xi)) - 1.0) < 0.003);
	CHECK(std::abs(rig.fisheye.cx - truth.fisheye.cx) < 1.0);
	CHECK(std::abs(rig.fisheye.cy - truth.fisheye.cy) < 1.0);
	CHECK(std::abs(rig.fisheye.max_angle_deg - truth.fisheye.max_angle_deg) < 1.0);
	// rgb_from_fisheye within 2 mm and 0.2 degrees.
	const double translation_mm = glm::length(rig.rgb_from_fisheye.translation - truth.rgb_from_fisheye.translation) * 1000.0;
	const double rotation_deg = angle_deg(rig.rgb_from_fisheye.rotation, truth.rgb_from_fisheye.rotation);
	MESSAGE("rgb_from_fisheye: " << translation_mm << " mm and " << rotation_deg << " deg off the truth; std " << report.rgb_from_fisheye_translation_std_m.x * 1000.0
								 << ", " << report.rgb_from_fisheye_translation_std_m.y * 1000.0 << ", " << report.rgb_from_fisheye_translation_std_m.z * 1000.0
								 << " mm; pairs RMS " << report.pair_rgb_rms_px << " / " << report.pair_fisheye_rms_px << " px");
	CHECK(translation_mm < 2.0);
	CHECK(rotation_deg < 0.2);
	// Every reprojection RMS is sub-pixel, and every uncertainty is a positive, finite number.
	CHECK(report.rgb_rms_px < 0.5);
	CHECK(report.fisheye_rms_px < 0.5);
	CHECK(report.pair_rgb_rms_px < 0.5);
	CHECK(report.pair_fisheye_rms_px < 0.5);
	for (double s : { report.rgb_std.fx, report.rgb_std.cx, report.fisheye_std.fx, report.fisheye_std.xi, report.rgb_from_fisheye_translation_std_m.x,
				 report.rgb_from_fisheye_rotation_std_deg.z }) {
		CHECK(std::isfinite(s));
		CHECK(s > 0.0);
	}
	// The synthetic depth is unbiased (Kinect-like noise only): scale 1 and offset 0 come back.
	REQUIRE(report.depth_checked);
	MESSAGE("depth: scale " << report.depth_scale << ", offset " << report.depth_offset_m * 1000.0 << " mm, residual " << report.depth_residual_rms_m * 1000.0
							<< " mm over " << report.depth_samples << " pixels");
	CHECK(std::abs(report.depth_scale - 1.0) < 0.01);
	CHECK(std::abs(report.depth_offset_m) < 0.005);
	CHECK(report.depth_residual_rms_m < 0.01);
}

TEST_CASE("calibration: degenerate input is refused with its reason") {
	const CalibrationViews &views = synthetic_views();
	REQUIRE_MESSAGE(views.error.empty(), views.error);
	SUBCASE("too few views") {
		const std::vector<BoardView> three(views.rgb.begin(), views.rgb.begin() + 3);
		const PinholeCalibration fit = calibrate_pinhole(views.board, views.rgb_size, three);
		CHECK(contains(fit.error, "RGB camera: too few views"));
		CHECK(contains(fit.error, "3"));
	}
	SUBCASE("the board always at the centre of the image") {
		// The same views squeezed towards the image's centre: a fit would have nothing at the edges.
		std::vector<BoardView> central = views.rgb;
		for (BoardView &view : central) {
			for (cv::Point2f &c : view.corners) {
				c = cv::Point2f(320.0f, 240.0f) + 0.3f * (c - cv::Point2f(320.0f, 240.0f));
			}
		}
		CHECK(contains(calibrate_pinhole(views.board, views.rgb_size, central).error, "always near the centre"));
		std::vector<BoardView> fisheye_central = views.fisheye;
		for (BoardView &view : fisheye_central) {
			for (cv::Point2f &c : view.corners) {
				c = cv::Point2f(511.5f, 511.5f) + 0.2f * (c - cv::Point2f(511.5f, 511.5f));
			}
		}
		const OmniCalibration fit = calibrate_omni(views.board, views.fisheye_size, fisheye_central, views.fisheye_circle);
		CHECK(contains(fit.error, "fisheye: the board is always near the centre"));
	}
	SUBCASE("no view seen by both cameras") {
		CalibrationViews without_pairs = views;
		without_pairs.pairs.clear();
		const RigCalibration calibrated = calibrate_rig(without_pairs, RigCalibrationOptions());
		CHECK(contains(calibrated.error, "no view where both cameras see the whole board"));
	}
	SUBCASE("a board that looks the same turned by half a turn cannot pair the cameras") {
		BoardSpec symmetric = views.board;
		symmetric.inner_y = 7; // 9x7: odd by odd
		CHECK(contains(calibrate_rgb_from_fisheye(symmetric, test_rig().rgb, test_rig().fisheye, views.pairs).error, "half a turn"));
	}
	SUBCASE("a square board, and a folder with nothing to calibrate from") {
		CHECK(contains(check_board(BoardSpec{ 7, 7, 0.03 }), "7x7 inner corners"));
		const fs::path empty = fs::temp_directory_path() / ("roomprobe_test_calibration_empty_" + std::to_string(::getpid()));
		fs::create_directories(empty);
		const CalibrationViews none = load_calibration_views(empty.string(), CalibrationViewsOptions());
		CHECK(contains(none.error, "no views"));
		CHECK(contains(none.error, empty.string()));
		CHECK(contains(load_calibration_views((empty / "missing").string(), CalibrationViewsOptions()).error, "missing: no such folder"));
		// Issue #38: a device is named for what it is.
		CHECK(contains(load_calibration_views("/dev/zero", CalibrationViewsOptions()).error, "/dev/zero: not a folder (a character device)"));
		fs::remove_all(empty);
	}
}

TEST_CASE("calibration: the rig file keeps the calibration's report, and loads as before") {
	const CalibrationViews &views = synthetic_views();
	REQUIRE_MESSAGE(views.error.empty(), views.error);
	const RigCalibration calibrated = calibrate_rig(views, RigCalibrationOptions());
	REQUIRE_MESSAGE(calibrated.error.empty(), calibrated.error);
	const fs::path path = fs::temp_directory_path() / ("roomprobe_test_calibrated_rig_" + std::to_string(::getpid()) + ".yaml");
	REQUIRE(save_rig(path.string(), calibrated.rig, &calibrated.report).empty());
	const RigLoadResult loaded = load_rig(path.string());
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	CHECK(loaded.rig.rgb.fx == doctest::Approx(calibrated.rig.rgb.fx));
	CHECK(loaded.rig.fisheye.xi == doctest::Approx(calibrated.rig.fisheye.xi));
	CHECK(glm::length(loaded.rig.rgb_from_fisheye.translation - calibrated.rig.rgb_from_fisheye.translation) < 1e-9);
	cv::FileStorage file(path.string(), cv::FileStorage::READ);
	const cv::FileNode report = file["calibration_report"];
	REQUIRE(report.isMap());
	CHECK(double(report["rgb_rms_px"]) == doctest::Approx(calibrated.report.rgb_rms_px));
	CHECK(int(report["pair_views"]) == int(views.pairs.size()));
	CHECK(double(report["depth"]["scale"]) == doctest::Approx(calibrated.report.depth_scale));
	fs::remove(path);
}

namespace {

const std::string k_ocamcalib_dir = std::string(ROOMPROBE_SHARED_DATA) + "/fisheye-ocamcalib";
bool ocamcalib_missing() {
	const bool missing = !fs::exists(k_ocamcalib_dir + "/calib_results.txt");
	if (missing) {
		std::fprintf(stderr, "test_calibration_rig: skipping the real fisheye images: %s is missing\n", k_ocamcalib_dir.c_str());
	}
	return missing;
}

} // namespace

TEST_CASE("calibration: the real OCamCalib images calibrate the fisheye in the unified model to a sub-0.3 px RMS" * doctest::skip(ocamcalib_missing())) {
	// Their board: 7 x 9 squares of 117 mm (test_camera_scaramuzza.cpp says why not checkerboard_sizes.txt's 5 x 7).
	const BoardSpec board{ 6, 8, 0.117 };
	std::vector<BoardView> views;
	cv::Mat brightest;
	cv::Size size;
	for (const fs::directory_entry &entry : fs::directory_iterator(k_ocamcalib_dir)) {
		if (entry.path().extension() != ".jpg") {
			continue;
		}
		const cv::Mat image = cv::imread(entry.path().string(), cv::IMREAD_GRAYSCALE);
		REQUIRE(!image.empty());
		size = image.size();
		keep_brightest(brightest, image);
		const BoardDetection found = detect_board(image, board);
		if (found.found) {
			views.push_back({ entry.path().filename().string(), found.corners });
		}
	}
	CHECK(views.size() >= 14);
	const ImageCircle circle = find_image_circle(brightest);
	MESSAGE("image circle (" << circle.cx << ", " << circle.cy << ") r " << circle.radius << " px; " << views.size() << " boards found");
	const OmniCalibration fit = calibrate_omni(board, size, views, circle);
	REQUIRE_MESSAGE(fit.error.empty(), fit.error);
	MESSAGE("cv::omnidir::calibrate on the real images: RMS " << fit.rms_px << " px over " << fit.views_used << " views; xi " << fit.camera.xi << ", fx "
															  << fit.camera.fx << ", max angle " << fit.camera.max_angle_deg << " deg");
	CHECK(fit.rms_px <= 0.3);
	CHECK(fit.views_used >= 12);
	// The same lens as OCamCalib's calibration says: the image centre within a few pixels.
	const ScaramuzzaLoadResult ocam = load_ocamcalib(k_ocamcalib_dir + "/calib_results.txt");
	REQUIRE(ocam.ok);
	CHECK(std::abs(fit.camera.cx - ocam.model.yc) < 5.0);
	CHECK(std::abs(fit.camera.cy - ocam.model.xc) < 5.0);
}

TEST_CASE("calibration: the fisheye's response, vignetting and colour gains come back within 2 % of the truth") {
	const CalibrationViews &views = synthetic_views();
	REQUIRE_MESSAGE(views.error.empty(), views.error);
	const RigCalibration calibrated = calibrate_rig(views, RigCalibrationOptions());
	REQUIRE_MESSAGE(calibrated.error.empty(), calibrated.error);
	const RigPhotometry &photometry = calibrated.rig.photometry;
	REQUIRE(photometry.known);
	CHECK(calibrated.report.photometry.find("Debevec") != std::string::npos);
	const synth::FisheyeOptions truth_options = fisheye_truth();
	// The truth in the rig's unit (the RGB camera's linear value: radiance at exposure 1).
	const CameraPhotometry truth = tone_curve_photometry(truth_options.tone_curve, 1.0, truth_options.channel_gains);
	const CameraPhotometry &fisheye = photometry.fisheye;
	// The response's shape, and the whole linearisation (response times gain), over the codes an
	// 8-bit camera resolves (below 16 a code step is more than 2 % of the value).
	double worst_shape = 0.0, worst_radiance = 0.0;
	for (int c = 0; c < 3; c++) {
		for (int k = 16; k <= 240; k++) {
			const double shape = (fisheye.response[c][k] / fisheye.response[c][128]) / (truth.response[c][k] / truth.response[c][128]);
			const double radiance = (fisheye.response[c][k] * fisheye.channel_gains[c]) / (truth.response[c][k] * truth.channel_gains[c]);
			worst_shape = std::max(worst_shape, std::abs(shape - 1.0));
			worst_radiance = std::max(worst_radiance, std::abs(radiance - 1.0));
		}
	}
	MESSAGE("response shape within " << 100.0 * worst_shape << " %, radiance within " << 100.0 * worst_radiance << " % (codes 16..240)");
	CHECK(worst_shape < 0.02);
	CHECK(worst_radiance < 0.02);
	// Vignetting over the image circle, against the renderer's model.
	REQUIRE(fisheye.vignetting.size() >= 2);
	double worst_vignetting = 0.0;
	for (int i = 0; i <= 100; i++) {
		const double r = i / 100.0;
		const glm::dvec2 pixel(calibrated.rig.fisheye.circle_cx + r * calibrated.rig.fisheye.circle_radius, calibrated.rig.fisheye.circle_cy);
		const double expected = synth::fisheye_vignetting(test_rig().fisheye, pixel, truth_options.vignetting_edge_gain);
		worst_vignetting = std::max(worst_vignetting, std::abs(vignetting_at(fisheye.vignetting, r) / expected - 1.0));
	}
	MESSAGE("vignetting within " << 100.0 * worst_vignetting << " % over the image circle");
	CHECK(worst_vignetting < 0.02);
	// The frames' exposures scale from the reference the pairs were taken at.
	CHECK(fisheye.reference_exposure_us == doctest::Approx(synth::SYNTH_EXPOSURE_UNIT_US));
	CHECK(exposure_ratio(fisheye, 4.0 * synth::SYNTH_EXPOSURE_UNIT_US, 0.0) == doctest::Approx(4.0));
	CHECK(exposure_ratio(fisheye, 4.0 * synth::SYNTH_EXPOSURE_UNIT_US, 6.0) == doctest::Approx(4.0 * std::pow(10.0, 6.0 / 20.0)));
	CHECK(exposure_ratio(fisheye, std::nan(""), 0.0) == 1.0);
	// The rig file keeps it (schema version 2) and the linearizer applies it.
	const fs::path path = fs::temp_directory_path() / ("roomprobe_test_photometry_" + std::to_string(::getpid()) + ".yaml");
	REQUIRE(save_rig(path.string(), calibrated.rig, &calibrated.report) == "");
	const RigLoadResult loaded = load_rig(path.string());
	fs::remove(path);
	REQUIRE_MESSAGE(loaded.ok, loaded.error);
	CHECK(loaded.rig.photometry.known);
	CHECK(loaded.rig.photometry.fisheye.vignetting.size() == fisheye.vignetting.size());
	CHECK(loaded.rig.photometry.fisheye.response[1][200] == doctest::Approx(fisheye.response[1][200]));
	CHECK(loaded.rig.photometry.fisheye.channel_gains.z == doctest::Approx(fisheye.channel_gains.z));
}

TEST_CASE("calibration: photometric views that cannot be fitted are refused with their reason") {
	const fs::path folder = fs::temp_directory_path() / ("roomprobe_test_photometric_" + std::to_string(::getpid()));
	fs::remove_all(folder);
	fs::create_directories(folder / "exposure");
	const OmniParams lens = test_rig().fisheye;
	const auto write = [&](const std::string &p_text) {
		std::ofstream(folder / "photometric.yaml") << p_text;
	};
	const cv::Size size(lens.width, lens.height);
	// No file: not present, no error.
	CHECK_FALSE(load_photometric_views(folder.string(), size).present);
	write("%YAML:1.0\nexposure_sweep: []\n");
	CHECK(contains(load_photometric_views(folder.string(), size).error, "reference_exposure_us: missing"));
	write("%YAML:1.0\nreference_exposure_us: 100\nexposure_sweep:\n  - { image: exposure/000.png, exposure_us: 100 }\n");
	CHECK(contains(load_photometric_views(folder.string(), size).error, "exposure/000.png: missing"));
	cv::imwrite((folder / "exposure/000.png").string(), cv::Mat(16, 16, CV_8UC3, cv::Scalar::all(100)));
	CHECK(contains(load_photometric_views(folder.string(), size).error, "16x16, the fisheye's images are"));
	// Too few exposures, or too narrow a sweep.
	const std::vector<cv::Mat> one(2, cv::Mat(size, CV_8UC3, cv::Scalar::all(100)));
	CHECK(contains(fit_response(one, { 100.0, 200.0 }, lens).error, "at least 3 images"));
	const std::vector<cv::Mat> three(3, cv::Mat(size, CV_8UC3, cv::Scalar::all(100)));
	CHECK(contains(fit_response(three, { 100.0, 200.0, 400.0 }, lens).error, "less than 4 stops"));
	// A flat field that is all clipped shows no fall-off.
	std::array<ResponseCurve, 3> linear;
	for (ResponseCurve &curve : linear) {
		curve = tone_curve_response(ToneCurve::Srgb);
	}
	CHECK(contains(fit_vignetting(cv::Mat(size, CV_8UC3, cv::Scalar::all(255)), linear, lens).error, "no usable pixel"));
	fs::remove_all(folder);
}

TEST_CASE("calibration: a recording of the board held before the rig gives the same calibration from its own frames") {
	const CalibrationViews &views = synthetic_views();
	REQUIRE_MESSAGE(views.error.empty(), views.error);
	// The rendered views as a recording's frames: the RGB camera's alone, the fisheye's alone, and
	// the pairs, each pair's fisheye frame 5 ms from its RGB-D frame on the RGB-D clock.
	const fs::path source = rendered_views().folder / "calibration";
	const fs::path folder = fs::temp_directory_path() / ("roomprobe_test_board_recording_" + std::to_string(::getpid()));
	fs::remove_all(folder);
	const Rig truth = test_rig();
	RecordingWriter writer;
	REQUIRE(writer.open_without_room(folder.string(), truth).ok);
	const auto rgb_of = [](const fs::path &p_path) {
		cv::Mat rgb;
		cv::cvtColor(cv::imread(p_path.string(), cv::IMREAD_COLOR), rgb, cv::COLOR_BGR2RGB);
		return rgb;
	};
	char name[64];
	for (int v = 0; v < 8; v++) {
		RgbdFrame frame;
		frame.timestamp_s = 0.5 * v;
		std::snprintf(name, sizeof(name), "rgb/%03d.png", v);
		frame.rgb = rgb_of(source / name);
		frame.depth_m = cv::Mat(frame.rgb.size(), CV_32FC1, cv::Scalar(std::nan("")));
		REQUIRE(writer.add_rgbd(frame).ok);
	}
	for (int p = 0; p < 6; p++) {
		RgbdFrame frame;
		frame.timestamp_s = 20.0 + 0.5 * p;
		std::snprintf(name, sizeof(name), "pairs/%03d_rgb.png", p);
		frame.rgb = rgb_of(source / name);
		std::snprintf(name, sizeof(name), "pairs/%03d_depth.png", p);
		frame.depth_m = cv::imread((source / name).string(), cv::IMREAD_UNCHANGED);
		REQUIRE(writer.add_rgbd(frame).ok);
	}
	for (int v = 0; v < 8; v++) {
		FisheyeFrame frame;
		frame.timestamp_s = 10.0 + 0.5 * v;
		std::snprintf(name, sizeof(name), "fisheye/%03d.png", v);
		frame.image = rgb_of(source / name);
		REQUIRE(writer.add_fisheye(frame).ok);
	}
	for (int p = 0; p < 6; p++) {
		FisheyeFrame frame;
		frame.timestamp_s = 20.0 + 0.5 * p - truth.fisheye_time_offset_s + 0.005;
		std::snprintf(name, sizeof(name), "pairs/%03d_fisheye.png", p);
		frame.image = rgb_of(source / name);
		REQUIRE(writer.add_fisheye(frame).ok);
	}
	REQUIRE(writer.close().ok);

	// Which board: the recording does not say, and the caller did not either.
	CHECK(contains(load_calibration_views(folder.string(), CalibrationViewsOptions()).error, "which board?"));
	CalibrationViewsOptions options;
	options.board = views.board;
	options.board_given = true;
	const CalibrationViews from_frames = load_calibration_views(folder.string(), options);
	fs::remove_all(folder);
	REQUIRE_MESSAGE(from_frames.error.empty(), from_frames.error);
	CHECK(from_frames.rgb.size() == views.rgb.size());
	CHECK(from_frames.fisheye.size() == views.fisheye.size());
	CHECK(from_frames.pairs.size() == views.pairs.size());
	const RigCalibration calibrated = calibrate_rig(from_frames, RigCalibrationOptions());
	REQUIRE_MESSAGE(calibrated.error.empty(), calibrated.error);
	const Rig &rig = calibrated.rig;
	CHECK(std::abs(rig.rgb.fx / truth.rgb.fx - 1.0) < 0.003);
	CHECK(std::abs(rig.rgb.cx - truth.rgb.cx) < 1.0);
	CHECK(std::abs(rig.fisheye.fx / (1.0 + rig.fisheye.xi) / (truth.fisheye.fx / (1.0 + truth.fisheye.xi)) - 1.0) < 0.003);
	CHECK(glm::length(rig.rgb_from_fisheye.translation - truth.rgb_from_fisheye.translation) < 0.002);
	CHECK(angle_deg(rig.rgb_from_fisheye.rotation, truth.rgb_from_fisheye.rotation) < 0.2);
	CHECK(calibrated.report.depth_checked); // the pairs' depth came through the recording
}

// Issue #38: board sizes were echoed as numbers the user never typed ("%g mm" of --square-m, a
// count of 9.7 in board.yaml read as 10, "nine" as 0). The board is echoed as given: the counts,
// and the square's side in metres as the shortest text that reads back as the same number.
TEST_CASE("calibration board: echoed as the user gave it; a board file's wrong counts are refused, naming the field and what it holds") {
	CHECK(board_text(BoardSpec{ 9, 6, 0.035 }) == "9x6 inner corners, 0.035 m squares");
	CHECK(board_text(BoardSpec{ 9, 6, 0.0254 }) == "9x6 inner corners, 0.0254 m squares");
	CHECK(board_text(BoardSpec{ 9, 6, 0.0123456789 }) == "9x6 inner corners, 0.0123456789 m squares");
	CHECK(check_board(BoardSpec{ 7, 7, 0.03 }) ==
			"board 7x7 inner corners, 0.03 m squares: as many across as down, so the corners' order is ambiguous; use a board with one more square "
			"one way (e.g. 9x6)");
	CHECK(check_board(BoardSpec{ 9, 6, 12.5 }) == "board 9x6 inner corners, 12.5 m squares: the square's side must be within 0 and 10 m");
	CHECK(check_board(BoardSpec{ 200, 6, 0.035 }) == "board 200x6 inner corners, 0.035 m squares: at most 100 inner corners a side");

	const fs::path folder = fs::temp_directory_path() / ("roomprobe_test_board_file_" + std::to_string(::getpid()));
	fs::remove_all(folder);
	fs::create_directories(folder);
	const std::string board = (folder / "board.yaml").string();
	auto error_with = [&](const std::string &p_fields) {
		std::ofstream(board, std::ios::trunc) << "%YAML:1.0\n---\n" << p_fields;
		return load_calibration_views(folder.string(), CalibrationViewsOptions()).error;
	};
	CHECK(error_with("inner_corners_x: 9.7\ninner_corners_y: 6\nsquare_m: 0.035\n") ==
			board + ": inner_corners_x: must be a whole number of inner corners (got 9.7)");
	CHECK(error_with("inner_corners_x: 9\ninner_corners_y: nine\nsquare_m: 0.035\n") == board + ": inner_corners_y: must be an integer");
	CHECK(contains(error_with("inner_corners_x: 9\ninner_corners_y: 6\nsquare_m: .nan\n"), board + ": square_m: must be finite (got "));
	CHECK(error_with("inner_corners_x: 200\ninner_corners_y: 6\nsquare_m: 0.035\n") ==
			board + ": board 200x6 inner corners, 0.035 m squares: at most 100 inner corners a side");
	// A good board file is taken as written: the folder then has no views, and says so.
	CHECK(contains(error_with("inner_corners_x: 9\ninner_corners_y: 6\nsquare_m: 0.0254\n"), "no views"));
	fs::remove_all(folder);
}
