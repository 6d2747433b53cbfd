// roomprobe_calibrate: the rig file from checkerboard views of both cameras, in one command (paper
// §3.2; calibration/rig_calibration.h): the RGB camera's intrinsics, the fisheye's in the unified
// model (or imported from OCamCalib), rgb_from_fisheye from the views both cameras took at once,
// and the depth checked against the board's plane; the fisheye's photometry (response,
// vignetting, colour gains: calibration/photometric_calibration.h) when the views include
// photometric.yaml; with --recording, the clock offset between the cameras from the recording's
// own frames (calibration/clock_offset.h). The views' layout is in calib/README.md.
//
// usage: roomprobe_calibrate (--images DIR | --recording DIR) --out rig.yaml [--board 9x6]
//          [--square-m 0.035] [--depth-scale-m 0.001] [--ocamcalib calib_results.txt] [--force]
//   --images DIR      a folder of views: rgb/, fisheye/, pairs/NAME_{rgb,fisheye,depth}.png
//   --recording DIR   a recording whose calibration/ holds them (./roomprobe synth writes one); its
//                     frames, the rig moved by hand, give the clock offset
//   --clock-seconds S how much of the recording the clock offset uses (default 6)
//   --board CxR       the board's inner corners across and down (default: the folder's board.yaml)
//   --ocamcalib FILE  the fisheye from OCamCalib's calib_results.txt instead of its views
//   --force           overwrite an existing --out file (it never is otherwise)
// A progress line shows while the boards are found; the fits' figures follow, and the last line is
// a summary.

#include "../common/cli.h"

#include <calibration/calibration_views.h>
#include <calibration/clock_offset.h>
#include <calibration/rig_calibration.h>
#include <recording/recording_reader.h>

#include <cstdio>
#include <vector>
#include <filesystem>
#include <optional>
#include <string>

using namespace roomprobe;

namespace {

int usage_error(const std::string &p_message) {
	std::fprintf(stderr,
			"roomprobe_calibrate: %s\nusage: roomprobe_calibrate (--images DIR | --recording DIR) --out rig.yaml [--board 9x6] [--square-m 0.035] "
			"[--depth-scale-m 0.001] [--ocamcalib calib_results.txt] [--clock-seconds 6] [--force]\n",
			p_message.c_str());
	return 2;
}

// The command line's bounds (issue #38). A board's inner corners: OpenCV's search needs 2 or more
// a side, and no printed board has 100. A square from 1 mm to 1 m; the depth unit from 1 um to
// 1 m (0.001 for millimetres); the clock's search at most an hour of frames.
constexpr int BOARD_MIN_CORNERS = 2, BOARD_MAX_CORNERS = BOARD_MAX_INNER_CORNERS;
constexpr double SQUARE_MIN_M = 0.001, SQUARE_MAX_M = 1.0;
constexpr double DEPTH_SCALE_MIN_M = 1e-6, DEPTH_SCALE_MAX_M = 1.0;
constexpr double CLOCK_MAX_S = 3600.0;

bool parse_board(const std::string &p_text, BoardSpec *r_board) {
	const size_t x_at = p_text.find_first_of("xX");
	long x = 0, y = 0;
	if (x_at == std::string::npos || !cli::parse_integer(p_text.substr(0, x_at), &x) || !cli::parse_integer(p_text.substr(x_at + 1), &y)) {
		return false;
	}
	if (x < BOARD_MIN_CORNERS || y < BOARD_MIN_CORNERS || x > BOARD_MAX_CORNERS || y > BOARD_MAX_CORNERS) {
		return false;
	}
	r_board->inner_x = int(x);
	r_board->inner_y = int(y);
	return true;
}

// The command line, as given.
struct CalibrateArgs {
	std::string images, out, ocamcalib_path;
	bool force = false, board_given = false, square_given = false, is_recording = false;
	ClockOffsetOptions clock_options;
	CalibrationViewsOptions view_options;
	RigCalibrationOptions options;
};

// The command line into *r_args: the exit status when it is refused, else nothing.
std::optional<int> parse_arguments(int p_argc, char **p_argv, CalibrateArgs *r_args) {
	cli::Arguments args(p_argc, p_argv, 1);
	std::string arg;
	while (args.next(&arg)) {
		if (arg == "--images" || arg == "--recording") {
			if (!args.value(&r_args->images)) {
				return usage_error(arg + " needs a folder");
			}
			r_args->is_recording = arg == "--recording";
		} else if (arg == "--clock-seconds") {
			if (!args.positive_number(CLOCK_MAX_S, &r_args->clock_options.max_seconds)) {
				return usage_error("--clock-seconds needs a number of seconds in (0, " + std::to_string(int(CLOCK_MAX_S)) + "]");
			}
		} else if (arg == "--out") {
			if (!args.value(&r_args->out)) {
				return usage_error("--out needs a file");
			}
		} else if (arg == "--board") {
			std::string text;
			if (!args.value(&text) || !parse_board(text, &r_args->view_options.board)) {
				return usage_error("--board needs the inner corners as COLSxROWS, each " + std::to_string(BOARD_MIN_CORNERS) + " to " +
						std::to_string(BOARD_MAX_CORNERS) + ", e.g. 9x6");
			}
			r_args->board_given = true;
		} else if (arg == "--square-m") {
			if (!args.number_in(SQUARE_MIN_M, SQUARE_MAX_M, &r_args->view_options.board.square_m)) {
				return usage_error("--square-m needs the side of a square in metres in " + cli::range_text(SQUARE_MIN_M, SQUARE_MAX_M));
			}
			r_args->square_given = true;
		} else if (arg == "--depth-scale-m") {
			if (!args.number_in(DEPTH_SCALE_MIN_M, DEPTH_SCALE_MAX_M, &r_args->options.depth_scale_m)) {
				return usage_error("--depth-scale-m needs metres per depth unit in " + cli::range_text(DEPTH_SCALE_MIN_M, DEPTH_SCALE_MAX_M) +
						" (0.001 for millimetres)");
			}
		} else if (arg == "--ocamcalib") {
			if (!args.value(&r_args->ocamcalib_path)) {
				return usage_error("--ocamcalib needs OCamCalib's calib_results.txt");
			}
		} else if (arg == "--force") {
			r_args->force = true;
		} else {
			return usage_error("unknown argument '" + arg + "'");
		}
	}
	if (r_args->images.empty() || r_args->out.empty()) {
		return usage_error("--images (or --recording) and --out are needed");
	}
	if (r_args->board_given != r_args->square_given) {
		return usage_error("--board and --square-m go together (the folder's board.yaml is used when both are left out)");
	}
	return std::nullopt;
}

// The exit status when --out cannot be written, else nothing; checked before the fits.
std::optional<int> check_output(const CalibrateArgs &p_args) {
	const std::string &out = p_args.out;
	// Never into what it reads (--recording REC --out REC/rig.yaml would replace the recording's own
	// rig), even with --force, as bench's --save-trajectory.
	const std::string inside = cli::output_in_input_problem("--out", out, { p_args.images, p_args.ocamcalib_path });
	if (!inside.empty()) {
		return usage_error(inside);
	}
	const std::string unwritable = check_replaceable(out); // a folder or a device, even with --force
	if (!unwritable.empty()) {
		return usage_error("--out " + unwritable);
	}
	std::error_code ec;
	if (std::filesystem::exists(out, ec) && !p_args.force) {
		std::fprintf(stderr, "roomprobe_calibrate: %s: exists; it is not overwritten (remove it, or pass --force)\n", out.c_str());
		return 1;
	}
	// A folder that cannot be written (read-only, say) is refused now, not after the fits.
	const std::string cannot_write = cli::output_file_unwritable("--out", out);
	if (!cannot_write.empty()) {
		return usage_error(cannot_write);
	}
	return std::nullopt;
}

// The boards found in the views, and how many, printed; its error when the views cannot be used.
CalibrationViews find_boards(const CalibrateArgs &p_args) {
	CalibrationViewsOptions view_options = p_args.view_options;
	view_options.board_given = p_args.board_given;
	view_options.depth_scale_m = p_args.options.depth_scale_m;
	view_options.progress = [](size_t p_done, size_t p_total, const std::string &p_image) {
		std::printf("\r  finding the board: %zu / %zu  %-40s", p_done, p_total, p_image.c_str());
		std::fflush(stdout);
	};
	CalibrationViews views = load_calibration_views(p_args.images, view_options);
	std::printf("\n");
	if (!views.error.empty()) {
		return views;
	}
	// The board as given (issue #38: "%g mm" echoed sizes the user never typed).
	std::printf("board %s%s: found in %zu RGB and %zu fisheye images, %zu pairs; not in %zu\n", board_text(views.board).c_str(),
			views.board_from_file ? " (from the folder)" : "", views.rgb.size(), views.fisheye.size(), views.pairs.size(), views.missed.size());
	for (const std::string &missed : views.missed) {
		std::printf("  not used: %s\n", missed.c_str());
	}
	return views;
}

// A live recording's offset p_offset_s taken into the latencies (both streams on one clock).
void take_live_latencies(const Rig &p_recorded, double p_offset_s, Rig *r_rig, std::vector<std::string> *r_notes) {
	Rig &rig = *r_rig;
	// Live, both streams are stamped on the host's clock less each device's latency, and
	// the engine takes fisheye_time_offset_s as 0: what is left is the latencies'
	// difference. Fisheye stamp + offset = the frame's true time, so the fisheye's
	// latency is the offset less (or the RGB-D camera's the more, never below 0).
	rig.fisheye_time_offset_s = 0.0;
	rig.rgbd_latency_s = p_recorded.rgbd_latency_s;
	rig.fisheye_latency_s = p_recorded.fisheye_latency_s - p_offset_s;
	if (rig.fisheye_latency_s < 0.0) {
		rig.rgbd_latency_s -= rig.fisheye_latency_s;
		rig.fisheye_latency_s = 0.0;
	}
	r_notes->push_back("recorded live (one clock): the offset found is the cameras' latency difference, written as rgbd_latency_s " +
			std::to_string(rig.rgbd_latency_s) + " s and fisheye_latency_s " + std::to_string(rig.fisheye_latency_s) + " s; fisheye_time_offset_s stays 0");
}

// The clock offset from the recording p_args.images' own frames into *r_rig and *r_report, or a
// note saying why not.
void add_clock_offset(const CalibrateArgs &p_args, Rig *r_rig, RigCalibrationReport *r_report, std::vector<std::string> *r_notes) {
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_args.images);
	if (!opened.ok) {
		r_notes->push_back("clock offset not estimated: " + opened.error);
		return;
	}
	ClockOffsetOptions clock_options = p_args.clock_options;
	clock_options.progress = [](const std::string &p_line) {
		std::printf("  clock offset: %s\n", p_line.c_str());
		std::fflush(stdout);
	};
	const ClockOffsetEstimate clock = estimate_clock_offset(reader, *r_rig, clock_options);
	const RgbdFrameResult first = reader.read_rgbd(0);
	const bool live = first.ok && first.frame.capture.is_known(); // the devices reported: recorded live, one clock
	if (!clock.error.empty()) {
		r_notes->push_back("clock offset not estimated from the recording: " + clock.error);
		return;
	}
	if (live) {
		take_live_latencies(reader.get_rig(), clock.offset_s, r_rig, r_notes);
	}
	std::erase(*r_notes, r_report->clock_offset);
	if (!live) {
		r_rig->fisheye_time_offset_s = clock.offset_s;
	}
	char text[256];
	std::snprintf(text, sizeof(text), "from the recording's motion: %zu fisheye rotations against the RGB-D camera's, %.1f deg turned, residual %.3f deg, std %.2f ms",
			clock.steps_used, clock.turn_deg, clock.residual_rms_deg, clock.std_s * 1000.0);
	r_report->clock_offset = text;
	std::printf("clock offset: fisheye_time_offset_s %.4f s (+-%.2f ms), %s\n", clock.offset_s, clock.std_s * 1000.0, text);
}

// The fits' figures and the notes.
void print_calibration(const Rig &p_rig, const RigCalibrationReport &p_report, const std::vector<std::string> &p_notes) {
	const Rig &rig = p_rig;
	const RigCalibrationReport &r = p_report;
	std::printf("RGB camera: fx %.3f fy %.3f (+-%.3f %.3f) cx %.3f cy %.3f (+-%.3f %.3f) px, k1 %.5f k2 %.5f p1 %.6f p2 %.6f; RMS %.3f px over %zu views\n", rig.rgb.fx,
			rig.rgb.fy, r.rgb_std.fx, r.rgb_std.fy, rig.rgb.cx, rig.rgb.cy, r.rgb_std.cx, r.rgb_std.cy, rig.rgb.k1, rig.rgb.k2, rig.rgb.p1, rig.rgb.p2, r.rgb_rms_px,
			r.rgb_views);
	if (rig.has_fisheye()) {
		const OmniParams &f = rig.fisheye;
		std::printf("fisheye (%s): xi %.4f (+-%.4f) fx %.3f fy %.3f cx %.3f cy %.3f px; image circle (%.1f, %.1f) r %.1f px, %.1f deg; RMS %.3f px\n",
				r.fisheye_method.c_str(), f.xi, r.fisheye_std.xi, f.fx, f.fy, f.cx, f.cy, f.circle_cx, f.circle_cy, f.circle_radius, f.max_angle_deg, r.fisheye_rms_px);
		const glm::dvec3 &t = rig.rgb_from_fisheye.translation;
		std::printf("rgb_from_fisheye: t (%.4f, %.4f, %.4f) m (+-%.2f %.2f %.2f mm), rotation +-(%.3f %.3f %.3f) deg; RMS %.3f px RGB, %.3f px fisheye over "
					"%zu pairs\n",
				t.x, t.y, t.z, r.rgb_from_fisheye_translation_std_m.x * 1e3, r.rgb_from_fisheye_translation_std_m.y * 1e3, r.rgb_from_fisheye_translation_std_m.z * 1e3,
				r.rgb_from_fisheye_rotation_std_deg.x, r.rgb_from_fisheye_rotation_std_deg.y, r.rgb_from_fisheye_rotation_std_deg.z, r.pair_rgb_rms_px,
				r.pair_fisheye_rms_px, r.pair_views);
	}
	if (r.depth_checked) {
		std::printf("depth against the boards: measured = %.4f x board %+.2f mm; residual %.2f mm RMS (%.2f mm before the scale and offset) over %zu pixels\n",
				r.depth_scale, r.depth_offset_m * 1e3, r.depth_residual_rms_m * 1e3, r.depth_raw_rms_m * 1e3, r.depth_samples);
	}
	if (rig.photometry.known) {
		const glm::dvec3 &g = rig.photometry.fisheye.channel_gains;
		std::printf("fisheye photometry: %s; response residual %.4f (ln), vignetting %.2f %% at the rim (fit %.2f %% RMS), colour gains %.4f %.4f %.4f (fit %.2f %% RMS)\n",
				r.photometry.c_str(), r.response_fit_rms, rig.photometry.fisheye.vignetting.empty() ? 100.0 : 100.0 * rig.photometry.fisheye.vignetting.back(),
				100.0 * r.vignetting_fit_rms, g.x, g.y, g.z, 100.0 * r.colour_fit_rms);
	}
	for (const std::string &note : p_notes) {
		std::printf("note: %s\n", note.c_str());
	}
}

int run(int p_argc, char **p_argv) {
	CalibrateArgs args;
	if (const std::optional<int> done = parse_arguments(p_argc, p_argv, &args)) {
		return *done;
	}
	if (const std::optional<int> refused = check_output(args)) {
		return *refused;
	}
	ScaramuzzaModel ocamcalib;
	if (!args.ocamcalib_path.empty()) {
		const ScaramuzzaLoadResult loaded = load_ocamcalib(args.ocamcalib_path);
		if (!loaded.ok) {
			std::fprintf(stderr, "roomprobe_calibrate: %s\n", loaded.error.c_str());
			return 1;
		}
		ocamcalib = loaded.model;
		args.options.ocamcalib = &ocamcalib;
		args.options.ocamcalib_name = args.ocamcalib_path;
	}
	const CalibrationViews views = find_boards(args);
	if (!views.error.empty()) {
		std::fprintf(stderr, "roomprobe_calibrate: %s\n", views.error.c_str());
		return 1;
	}
	std::printf("fitting...\n");
	std::fflush(stdout);
	const RigCalibration calibration = calibrate_rig(views, args.options);
	if (!calibration.error.empty()) {
		std::fprintf(stderr, "roomprobe_calibrate: %s: %s\n", args.images.c_str(), calibration.error.c_str());
		return 1;
	}
	Rig rig = calibration.rig;
	RigCalibrationReport r = calibration.report;
	std::vector<std::string> notes = calibration.notes;
	if (args.is_recording && rig.has_fisheye()) {
		add_clock_offset(args, &rig, &r, &notes);
	}
	print_calibration(rig, r, notes);
	const std::string error = save_rig(args.out, rig, &r);
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_calibrate: %s\n", error.c_str());
		return 1;
	}
	std::printf("summary: out=%s rgb_rms_px=%.3f fisheye_rms_px=%.3f pair_rgb_rms_px=%.3f pair_fisheye_rms_px=%.3f depth_scale=%.4f depth_residual_mm=%.2f "
				"fisheye_time_offset_ms=%.2f photometry=%d ok=1\n",
			args.out.c_str(), r.rgb_rms_px, r.fisheye_rms_px, r.pair_rgb_rms_px, r.pair_fisheye_rms_px, r.depth_scale, r.depth_residual_rms_m * 1e3,
			rig.fisheye_time_offset_s * 1000.0, rig.photometry.known ? 1 : 0);
	return 0;
}

} // namespace

int main(int p_argc, char **p_argv) {
	return roomprobe::cli::guarded_main("roomprobe_calibrate", [&] { return run(p_argc, p_argv); });
}
