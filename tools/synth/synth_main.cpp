// roomprobe_synth: renders a synthetic RoomProbe recording with ground truth (extension/core/synth/).
//
//   roomprobe_synth --scene two_rooms|living_room|panorama_room --out DIR [--seconds 10] [--seed N]
//                   [--rig calib/synthetic_rig.yaml] [--hdri PATH|none] [--cubemap-size 128]
//                   [--fisheye-rate 12] [--rgbd-rate 30] [--fisheye-hdr] [--exr-float] [--no-calibration]
//                   [--threads N] [--exposure fixed|auto|bracket] [--bracket-ev -5,0]
//                   [--tone-curve srgb|log] [--fisheye-gains R,G,B] [--vignetting 0.5] [--room-sweep | --loop]
//                   [--frame-format zstd|png]

#include <io/opencv.h>

#include <rig/rig.h>
#include <synth/synth_sequence.h>

#include "../common/cli.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

constexpr const char *DEFAULT_HDRI = "../shared/data/hdri/lebombo_1k.hdr";

void usage(std::FILE *p_out) {
	std::fprintf(p_out,
			"usage: roomprobe_synth --scene two_rooms|living_room|panorama_room --out DIR [options]\n"
			"  --scene NAME        two_rooms (the paper's Figure 4), living_room, or panorama_room\n"
			"                      (flat walls showing the panorama, the camera sweeping along one)\n"
			"  --out DIR           the recording folder; must not exist or be empty\n"
			"  --seconds S         length of the recording (default 10)\n"
			"  --seed N            trajectory and noise seed, an unsigned integer (default 1)\n"
			"  --room-sweep        carry the rig through the room (both rooms in two_rooms), turning\n"
			"                      round, instead of the scene's own path: a sweep that shows\n"
			"                      every wall and the floor, for ./roomprobe room\n"
			"  --loop              one whole turn round the table over the recording's length, so that\n"
			"                      it ends where it began (loop closure with truth; living_room, two_rooms)\n"
			"  --rig PATH          rig file (default calib/synthetic_rig.yaml)\n"
			"  --look-up           with --room-sweep: the camera also tilts up to the ceiling every 5 s\n"
			"                      (a 1.6-s look, up to 55 degrees up), as when scanning with one camera\n"
			"  --no-fisheye        the rig's RGB-D camera alone: no fisheye stream, no calibration views;\n"
			"                      the ground-truth cubemaps at the same times as with the fisheye\n"
			"  --hdri PATH|none    living_room's window view, panorama_room's walls (default %s;\n"
			"                      none: a procedural sky in living_room's window)\n"
			"  --cubemap-size N    ground-truth cubemap face size in pixels (default 128)\n"
			"  --rgbd-rate HZ      RGB-D frame rate (default 30)\n"
			"  --fisheye-rate HZ   fisheye frame rate (default 12)\n"
			"  --frame-format F    how RGB, depth and 8-bit fisheye frames are stored: zstd (default: raw\n"
			"                      frames, zstd-compressed, fast to decode) or png (as recordings were\n"
			"                      before; image viewers open them); docs/recording-format.md\n"
			"  --fisheye-hdr       write fisheye frames as linear EXR instead of 8-bit images\n"
			"  --exr-float         write EXRs (cubemaps, HDR fisheye) as 32-bit float rather than half\n"
			"  --no-calibration    skip the checkerboard and photometric views (calibration/)\n"
			"  --exposure MODE     the fisheye's exposure: fixed (default), auto (auto-exposure) or bracket\n"
			"  --bracket-ev LIST   bracket's stops about the reference exposure, in turn (default -5,0)\n"
			"  --tone-curve NAME   the fisheye's response: srgb (default) or log\n"
			"  --fisheye-gains R,G,B  the fisheye's white balance against the RGB camera (default 1,1,1)\n"
			"  --vignetting GAIN   the fisheye's gain at its image circle's rim, (0, 1] (default 0.5)\n"
			"  --threads N         use at most N threads (default: all cores)\n"
			"  -h, --help          this text\n",
			DEFAULT_HDRI);
}

int fail(const std::string &p_message) {
	std::fprintf(stderr, "roomprobe_synth: %s\n", p_message.c_str());
	return 2;
}

bool parse_double(const std::string &p_text, double *r_value) {
	try {
		size_t used = 0;
		const double value = std::stod(p_text, &used);
		if (used != p_text.size() || !std::isfinite(value)) {
			return false;
		}
		*r_value = value;
		return true;
	} catch (...) {
		return false;
	}
}

bool parse_u64(const std::string &p_text, uint64_t *r_value) {
	if (p_text.empty() || p_text[0] == '-' || p_text[0] == '+') {
		return false;
	}
	try {
		size_t used = 0;
		const unsigned long long value = std::stoull(p_text, &used, 10);
		if (used != p_text.size()) {
			return false;
		}
		*r_value = value;
		return true;
	} catch (...) {
		return false;
	}
}

// The command line, as given.
struct SynthArgs {
	std::string scene_name, out, rig_path = "calib/synthetic_rig.yaml", hdri;
	bool hdri_given = false;
	bool room_sweep = false;
	bool loop = false;
	bool no_fisheye = false;
	bool look_up = false;
	roomprobe::synth::SequenceOptions options;
	double cubemap_size = 128.0;
	double threads = 0.0;
};

// Each *_option takes p_arg when it is one of its options (true), with *r_error set when its value
// is wrong; false leaves p_arg to the others.

// What is read and written: --scene, --out, --rig, --hdri.
bool file_option(roomprobe::cli::Arguments &p_cursor, const std::string &p_arg, SynthArgs *r_args, std::string *r_error) {
	if (p_arg == "--scene") {
		if (!p_cursor.value(&r_args->scene_name)) {
			*r_error = "--scene needs a value (two_rooms, living_room or panorama_room)";
		}
	} else if (p_arg == "--out") {
		if (!p_cursor.value(&r_args->out) || r_args->out.empty()) {
			*r_error = "--out needs a folder";
		}
	} else if (p_arg == "--rig") {
		if (!p_cursor.value(&r_args->rig_path)) {
			*r_error = "--rig needs a file";
		}
	} else if (p_arg == "--hdri") {
		if (!p_cursor.value(&r_args->hdri)) {
			*r_error = "--hdri needs a file (or none)";
		}
		r_args->hdri_given = true;
	} else {
		return false;
	}
	return true;
}

// How much is rendered and how: --seconds, --seed, --cubemap-size, --rgbd-rate, --fisheye-rate,
// --frame-format, --threads.
bool sampling_option(roomprobe::cli::Arguments &p_cursor, const std::string &p_arg, SynthArgs *r_args, std::string *r_error) {
	using namespace roomprobe;
	synth::SequenceOptions &options = r_args->options;
	std::string text;
	if (p_arg == "--seconds") {
		if (!p_cursor.value(&text) || !parse_double(text, &options.duration_s) || options.duration_s <= 0.0 || options.duration_s > 3600.0) {
			*r_error = "--seconds needs a number of seconds in (0, 3600], got '" + text + "'";
		}
	} else if (p_arg == "--seed") {
		if (!p_cursor.value(&text) || !parse_u64(text, &options.seed)) {
			*r_error = "--seed needs an unsigned integer, got '" + text + "'";
		}
	} else if (p_arg == "--cubemap-size") {
		double &size = r_args->cubemap_size;
		if (!p_cursor.value(&text) || !parse_double(text, &size) || size != std::floor(size) || size < 1 || size > 4096) {
			*r_error = "--cubemap-size needs a whole number of pixels in [1, 4096], got '" + text + "'";
		}
	} else if (p_arg == "--rgbd-rate") {
		if (!p_cursor.value(&text) || !parse_double(text, &options.rgbd_rate_hz) || options.rgbd_rate_hz <= 0.0 || options.rgbd_rate_hz > 1000.0) {
			*r_error = "--rgbd-rate needs a rate in (0, 1000] Hz, got '" + text + "'";
		}
	} else if (p_arg == "--fisheye-rate") {
		if (!p_cursor.value(&text) || !parse_double(text, &options.fisheye_rate_hz) || options.fisheye_rate_hz <= 0.0 || options.fisheye_rate_hz > 1000.0) {
			*r_error = "--fisheye-rate needs a rate in (0, 1000] Hz, got '" + text + "'";
		}
	} else if (p_arg == "--frame-format") {
		if (!p_cursor.value(&text) || !parse_frame_format(text, &options.frame_format)) {
			*r_error = "--frame-format needs zstd or png, got '" + text + "'";
		}
	} else if (p_arg == "--threads") {
		double &threads = r_args->threads;
		if (!p_cursor.value(&text) || !parse_double(text, &threads) || threads != std::floor(threads) || threads < 1 || threads > double(cli::MAX_THREADS)) {
			*r_error = "--threads needs a whole number in " + cli::range_text(1, double(cli::MAX_THREADS)) + ", got '" + text + "'";
		}
	} else {
		return false;
	}
	return true;
}

// The fisheye's exposure and response: --exposure, --bracket-ev, --tone-curve, --fisheye-gains,
// --vignetting.
bool fisheye_option(roomprobe::cli::Arguments &p_cursor, const std::string &p_arg, roomprobe::synth::SequenceOptions *r_options, std::string *r_error) {
	using namespace roomprobe;
	std::string text;
	if (p_arg == "--exposure") {
		if (!p_cursor.value(&text) || (text != "fixed" && text != "auto" && text != "bracket")) {
			*r_error = "--exposure needs fixed, auto or bracket, got '" + text + "'";
			return true;
		}
		r_options->exposure_mode = text == "auto" ? synth::ExposureMode::Auto : text == "bracket" ? synth::ExposureMode::Bracket : synth::ExposureMode::Fixed;
	} else if (p_arg == "--bracket-ev") {
		std::vector<double> stops;
		if (!p_cursor.value(&text) || !cli::parse_number_list(text, &stops) || stops.empty() || stops.size() > 16 ||
				std::any_of(stops.begin(), stops.end(), [](double p_ev) { return std::abs(p_ev) > 10.0; })) {
			*r_error = "--bracket-ev needs 1 to 16 stops within [-10, 10], comma-separated (e.g. -5,0), got '" + text + "'";
			return true;
		}
		r_options->bracket_ev = stops;
	} else if (p_arg == "--tone-curve") {
		if (!p_cursor.value(&text) || !parse_tone_curve(text, &r_options->fisheye.tone_curve)) {
			*r_error = "--tone-curve needs srgb or log, got '" + text + "'";
		}
	} else if (p_arg == "--fisheye-gains") {
		std::vector<double> gains;
		if (!p_cursor.value(&text) || !cli::parse_number_list(text, &gains) || gains.size() != 3 ||
				std::any_of(gains.begin(), gains.end(), [](double p_gain) { return !(p_gain > 0.0 && p_gain <= 10.0); })) {
			*r_error = "--fisheye-gains needs three gains in (0, 10], comma-separated (e.g. 1.1,1,0.85), got '" + text + "'";
			return true;
		}
		r_options->fisheye.channel_gains = glm::dvec3(gains[0], gains[1], gains[2]);
	} else if (p_arg == "--vignetting") {
		double &gain = r_options->fisheye.vignetting_edge_gain;
		if (!p_cursor.value(&text) || !parse_double(text, &gain) || !(gain > 0.0) || gain > 1.0) {
			*r_error = "--vignetting needs the gain at the image circle's rim, in (0, 1] (1: none), got '" + text + "'";
		}
	} else {
		return false;
	}
	return true;
}

// The switches: --fisheye-hdr, --exr-float, --room-sweep, --loop, --no-calibration.
bool flag_option(const std::string &p_arg, SynthArgs *r_args) {
	if (p_arg == "--fisheye-hdr") {
		r_args->options.fisheye_hdr = true;
	} else if (p_arg == "--exr-float") {
		r_args->options.exr_full_float = true;
	} else if (p_arg == "--room-sweep") {
		r_args->room_sweep = true;
	} else if (p_arg == "--loop") {
		r_args->loop = true;
	} else if (p_arg == "--no-fisheye") {
		r_args->no_fisheye = true;
	} else if (p_arg == "--look-up") {
		r_args->look_up = true;
	} else if (p_arg == "--no-calibration") {
		r_args->options.calibration_views = false;
	} else {
		return false;
	}
	return true;
}

// The command line into *r_args: the exit status when the tool ends here (--help, a bad option),
// else nothing.
std::optional<int> parse_arguments(int p_argc, char **p_argv, SynthArgs *r_args) {
	roomprobe::cli::Arguments cursor(p_argc, p_argv, 1);
	std::string arg;
	while (cursor.next(&arg)) {
		if (arg == "-h" || arg == "--help") {
			usage(stdout);
			return 0;
		}
		std::string error;
		if (!file_option(cursor, arg, r_args, &error) && !sampling_option(cursor, arg, r_args, &error) &&
				!fisheye_option(cursor, arg, &r_args->options, &error) && !flag_option(arg, r_args)) {
			usage(stderr);
			return fail("unknown argument '" + arg + "'");
		}
		if (!error.empty()) {
			return fail(error);
		}
	}
	r_args->options.cubemap_face_size = static_cast<int>(r_args->cubemap_size);
	return std::nullopt;
}

// The exit status when the options cannot run, else nothing: a scene and an output folder that is
// empty if it exists.
std::optional<int> check_arguments(const SynthArgs &p_args) {
	if (p_args.scene_name.empty() || p_args.out.empty()) {
		usage(stderr);
		return fail(p_args.scene_name.empty() ? "--scene is required" : "--out is required");
	}
	bool known = false;
	for (const std::string &name : roomprobe::synth::scene_names()) {
		known = known || name == p_args.scene_name;
	}
	if (!known) {
		return fail("unknown scene '" + p_args.scene_name + "' (known: two_rooms, living_room, panorama_room)");
	}
	namespace fs = std::filesystem;
	std::error_code ec;
	if (fs::exists(p_args.out, ec)) {
		if (!fs::is_directory(p_args.out, ec)) {
			return fail(p_args.out + ": exists and is not a folder");
		}
		if (!fs::is_empty(p_args.out, ec)) {
			return fail(p_args.out + ": the output folder exists and is not empty; choose another --out or remove it");
		}
	}
	return std::nullopt;
}

// The panorama the scene shows into r_scene->panorama_path (--hdri, or DEFAULT_HDRI where the
// scene needs one); the exit status when there is none to show.
std::optional<int> choose_panorama(const SynthArgs &p_args, roomprobe::synth::SceneOptions *r_scene) {
	namespace fs = std::filesystem;
	std::error_code ec;
	std::string hdri = p_args.hdri;
	if (p_args.scene_name == "living_room") {
		if (!p_args.hdri_given) {
			hdri = DEFAULT_HDRI;
			if (!fs::exists(hdri, ec)) {
				return fail(std::string("living_room shows a panorama in its window, and ") + DEFAULT_HDRI +
						" is missing: pass --hdri PATH (or --hdri none for a procedural sky)");
			}
		}
		r_scene->panorama_path = hdri == "none" ? "" : hdri;
	} else if (p_args.scene_name == "panorama_room") {
		if (hdri == "none") {
			return fail("panorama_room's walls are a panorama: --hdri none does not apply, pass --hdri PATH");
		}
		if (!p_args.hdri_given) {
			hdri = DEFAULT_HDRI;
			if (!fs::exists(hdri, ec)) {
				return fail(std::string("panorama_room's walls show a panorama, and ") + DEFAULT_HDRI + " is missing: pass --hdri PATH");
			}
		}
		r_scene->panorama_path = hdri;
	} else if (p_args.hdri_given) {
		return fail("--hdri " + hdri + ": the scene " + p_args.scene_name + " shows no panorama; --hdri applies to living_room and panorama_room");
	}
	if (!r_scene->panorama_path.empty() && !fs::exists(r_scene->panorama_path, ec)) {
		return fail("--hdri " + r_scene->panorama_path + ": no such file (an equirectangular .hdr or .exr panorama, or none)");
	}
	return std::nullopt;
}

// The counts and the time each stage took, p_total_s of them all.
void print_timings(const roomprobe::synth::SequenceTimings &p_timings, int p_cubemap_face_size, double p_total_s) {
	const roomprobe::synth::SequenceTimings &t = p_timings;
	std::printf("wrote %zu RGB-D frames, %zu fisheye frames, %zu ground-truth cubemaps (%d px faces), %zu calibration views\n",
			t.rgbd_frames, t.fisheye_frames, t.cubemaps, p_cubemap_face_size, t.calibration_views);
	std::printf("timings: scene %.2f s, RGB-D %.2f s (%.1f ms/frame), fisheye %.2f s (%.1f ms/frame), cubemaps %.2f s (%.1f ms each),\n"
				"         waiting for writes %.2f s, calibration %.2f s; total %.2f s\n",
			t.scene_s, t.rgbd_s, t.rgbd_frames ? 1000.0 * t.rgbd_s / t.rgbd_frames : 0.0, t.fisheye_s,
			t.fisheye_frames ? 1000.0 * t.fisheye_s / t.fisheye_frames : 0.0, t.cubemap_s, t.cubemaps ? 1000.0 * t.cubemap_s / t.cubemaps : 0.0,
			t.write_wait_s, t.calibration_s, p_total_s);
}

// The scene made and its recording written into p_args.out, with what it took.
int render(const SynthArgs &p_args, const roomprobe::Rig &p_rig, const roomprobe::synth::SceneOptions &p_scene_options) {
	using namespace roomprobe;
	synth::SequenceOptions options = p_args.options;
	const auto start = std::chrono::steady_clock::now();
	std::error_code ec;
	if (!p_scene_options.panorama_path.empty()) {
		options.scene_panorama_path = std::filesystem::absolute(p_scene_options.panorama_path, ec).lexically_normal().string();
	}
	synth::SceneResult scene = synth::make_scene(p_args.scene_name, p_scene_options);
	if (!scene.ok) {
		return fail(scene.error);
	}
	if (p_args.room_sweep) {
		scene.scene.trajectory = synth::TrajectoryKind::RoomSweep;
	}
	if (p_args.look_up) {
		if (!p_args.room_sweep) {
			return fail("--look-up tilts the room sweep's camera to the ceiling now and then: it needs --room-sweep");
		}
		scene.scene.room_sweep.look_up_every_s = 5.0;
	}
	if (p_args.loop) {
		if (scene.scene.trajectory != synth::TrajectoryKind::Orbit) {
			return fail("--loop turns round the table: " + p_args.scene_name + (p_args.room_sweep ? " with --room-sweep" : "") +
					" does not orbit one (living_room and two_rooms do)");
		}
		scene.scene.orbit_loop_s = options.duration_s;
	}
	options.progress = [](const std::string &p_line) {
		std::printf("  %s\n", p_line.c_str());
		std::fflush(stdout);
	};
	std::printf("roomprobe_synth: %s, %.3g s, seed %llu, %d threads -> %s\n", p_args.scene_name.c_str(), options.duration_s,
			static_cast<unsigned long long>(options.seed),
			static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)), p_args.out.c_str());
	if (scene.scene.panorama_scale > 0.0) {
		std::printf("  the walls' radiance: %.4g x the panorama (%s)\n", scene.scene.panorama_scale, p_scene_options.panorama_path.c_str());
	}
	const synth::SequenceResult result = synth::write_sequence(p_args.out, p_rig, scene.scene, options);
	if (!result.ok) {
		return fail(result.error);
	}
	print_timings(result.timings, options.cubemap_face_size, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
	return 0;
}

int run(int argc, char **argv) {
	using namespace roomprobe;
	SynthArgs args;
	if (const std::optional<int> done = parse_arguments(argc, argv, &args)) {
		return *done;
	}
	if (const std::optional<int> refused = check_arguments(args)) {
		return *refused;
	}
	const RigLoadResult rig = load_rig(args.rig_path);
	if (!rig.ok) {
		return fail(rig.error);
	}
	synth::SceneOptions scene_options;
	scene_options.duration_s = args.options.duration_s;
	if (const std::optional<int> refused = choose_panorama(args, &scene_options)) {
		return *refused;
	}
	std::unique_ptr<tbb::global_control> thread_limit;
	if (args.threads > 0.0) {
		thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(args.threads));
	}
	return render(args, args.no_fisheye ? rgbd_camera_alone(rig.rig) : rig.rig, scene_options);
}

} // namespace

int main(int argc, char **argv) {
	return roomprobe::cli::guarded_main("roomprobe_synth", [&] { return run(argc, argv); });
}
