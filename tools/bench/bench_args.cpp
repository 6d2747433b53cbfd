// roomprobe_bench's command line: the usage, each benchmark's options and their bounds.

#include "bench_common.h"
#include "bench_decode.h"

#include "../common/cli.h"

#include <io/input_path.h>
#include <io/opencv.h>

namespace roomprobe::bench {

namespace {

// The command line's bounds (issue #38: every number that sizes memory, a pool or a run is bounded).
// --voxel-size-m: 1 mm is finer than a depth camera's noise (several mm at 1 m), and each halving asks
// 8x the blocks (1e-9 m asked 10^21x); 2 cm is half the truncation band (TsdfOptions, 4 cm), which
// then spans two voxels either side of a surface.
constexpr double VOXEL_MIN_M = 0.001, VOXEL_MAX_M = 0.02;
// --frames, --warmup-frames: 10^7 RGB-D frames is over 3 days at 30 Hz; the soak's series grow with them.
constexpr long MAX_FRAMES = 10000000;
// The probes' maps of one run together (--probes x --probe-size), bytes.
constexpr double MAX_PROBE_BYTES = 8.0 * 1073741824.0;
// --speed: 100x slower than real time (an event 1 s apart waits 100 s) to 1000x faster.
constexpr double SPEED_MIN = 0.01, SPEED_MAX = 1000.0;

// What an option parser did with an argument: took it, left it (not one of its options), or
// anything else: the exit status (usage's, or 0 after --help).
constexpr int TAKEN = -1, NOT_MINE = -2;

// Why --save-trajectory cannot be written, or "": it must not lie in what the benchmark reads (a
// recording's rgb.txt was once overwritten), and an existing file is kept unless --force.
std::string save_trajectory_problem(const Arguments &p_args) {
	const std::string &path = p_args.save_trajectory;
	if (path.empty()) {
		return "";
	}
	const std::string inside = cli::output_in_input_problem("--save-trajectory", path,
			{ p_args.recording, p_args.tum, p_args.seven_scenes, p_args.rig_file, p_args.open3d_results });
	return inside.empty() ? cli::output_file_problem("--save-trajectory", path, p_args.force) : inside;
}

// A folder or file option's value into *r_value.
int text_option(cli::Arguments &p_cursor, const char *p_error, std::string *r_value) {
	return p_cursor.value(r_value) ? TAKEN : usage(p_error);
}

// A whole-number option's value in [p_min, p_max] into *r_value.
template <typename Integer>
int integer_option(cli::Arguments &p_cursor, long p_min, long p_max, const std::string &p_error, Integer *r_value) {
	long n = 0;
	if (!p_cursor.integer_in(p_min, p_max, &n)) {
		return usage(p_error.c_str());
	}
	*r_value = Integer(n);
	return TAKEN;
}

// --frames N (every benchmark).
int frames_option(cli::Arguments &p_cursor, long *r_frames) {
	return integer_option(p_cursor, 1, MAX_FRAMES, "--frames needs a whole number of frames in " + cli::range_text(1, MAX_FRAMES), r_frames);
}

// --threads N (every benchmark).
int threads_option(cli::Arguments &p_cursor, int *r_threads) {
	return integer_option(p_cursor, 1, cli::MAX_THREADS, "--threads needs a whole number of threads in " + cli::range_text(1, cli::MAX_THREADS), r_threads);
}

// The sources and what is written: --recording, --tum, --7scenes, --rig, --intrinsics,
// --save-trajectory, --force, --open3d-results, --no-peers.
int source_option(cli::Arguments &p_cursor, const std::string &p_arg, Arguments *r_args) {
	const bool slam = r_args->mode == "slam";
	if (p_arg == "--recording") {
		return text_option(p_cursor, "--recording needs a folder", &r_args->recording);
	} else if (p_arg == "--tum" && slam) {
		return text_option(p_cursor, "--tum needs a folder", &r_args->tum);
	} else if (p_arg == "--7scenes" && slam) {
		return text_option(p_cursor, "--7scenes needs a folder", &r_args->seven_scenes);
	} else if (p_arg == "--rig") {
		return text_option(p_cursor, "--rig needs a rig file", &r_args->rig_file);
	} else if (p_arg == "--intrinsics") {
		double *k = r_args->intrinsics;
		if (!p_cursor.number_list(4, k) || !(k[0] > 0.0) || !(k[1] > 0.0)) {
			return usage("--intrinsics needs FX,FY,CX,CY in pixels, the focal lengths > 0");
		}
		r_args->has_intrinsics = true;
	} else if (p_arg == "--save-trajectory" && slam) {
		return text_option(p_cursor, "--save-trajectory needs a file", &r_args->save_trajectory);
	} else if (p_arg == "--force" && slam) {
		r_args->force = true;
	} else if (p_arg == "--open3d-results" && slam) {
		return text_option(p_cursor, "--open3d-results needs a file (tools/bench/open3d_peer.py --out)", &r_args->open3d_results);
	} else if (p_arg == "--no-peers" && slam) {
		r_args->peers = false;
	} else {
		return NOT_MINE;
	}
	return TAKEN;
}

// How much is run: --frames, --threads, --probes, --warmup-frames, --probe-size, --speed.
int run_option(cli::Arguments &p_cursor, const std::string &p_arg, Arguments *r_args) {
	if (p_arg == "--frames") {
		return frames_option(p_cursor, &r_args->frames);
	}
	if (p_arg == "--threads") {
		return threads_option(p_cursor, &r_args->threads);
	}
	if (p_arg == "--probes" && r_args->mode == "slam") {
		return integer_option(p_cursor, 1, 64, "--probes needs a probe count, 1 to 64", &r_args->probes);
	}
	if (p_arg == "--warmup-frames" && r_args->mode == "soak") {
		return integer_option(p_cursor, 1, MAX_FRAMES, "--warmup-frames needs a whole number of frames in " + cli::range_text(1, MAX_FRAMES),
				&r_args->warmup_frames);
	}
	if (p_arg == "--probe-size") {
		return integer_option(p_cursor, 1, 4096, "--probe-size needs a face size in texels, 1 to 4096", &r_args->probe_size);
	}
	if (p_arg == "--backend") {
		std::string name;
		p_cursor.value(&name);
		return compute_backend_from_name(name, &r_args->backend) ? TAKEN : usage("--backend needs cpu, vulkan or auto");
	}
	if (p_arg == "--speed" && r_args->mode == "live") {
		const std::string error = "--speed needs a playback speed in " + cli::range_text(SPEED_MIN, SPEED_MAX);
		return p_cursor.number_in(SPEED_MIN, SPEED_MAX, &r_args->speed) ? TAKEN : usage(error.c_str());
	}
	return NOT_MINE;
}

// DenseSlamOptions: --voxel-size-m, --colour-always, --scalar-icp, --max-speed, --noise-reference-m,
// --colour-weight, --icp-depth-range, --tsdf-depth-range, --max-jump, --colour-slide, --min-constraint,
// --raycast-level, --finest-stride, --points-normals.
int slam_option(cli::Arguments &p_cursor, const std::string &p_arg, DenseSlamOptions *r_slam) {
	if (p_arg == "--voxel-size-m") {
		double v = 0.0;
		if (!p_cursor.number_in(VOXEL_MIN_M, VOXEL_MAX_M, &v)) {
			return usage(("--voxel-size-m needs a voxel edge in metres in " + cli::range_text(VOXEL_MIN_M, VOXEL_MAX_M)).c_str());
		}
		r_slam->tsdf.voxel_size_m = float(v);
	} else if (p_arg == "--colour-always") {
		r_slam->icp.colour_always = true;
	} else if (p_arg == "--young-model") {
		double young[2];
		if (!p_cursor.number_list(2, young) || !(young[0] >= 0.0 && young[0] <= 1e6) || young[0] != double(int(young[0])) || !(young[1] >= 0.0)) {
			return usage("--young-model needs FRAMES,FACTOR: a whole number of fused frames and a factor, both >= 0 (0,0: off)");
		}
		r_slam->young_model_frames = int(young[0]);
		r_slam->young_model_noise_factor = young[1];
	} else if (p_arg == "--points-normals") {
		r_slam->reference_normals_from_points = true;
	} else if (p_arg == "--scalar-icp") {
		r_slam->icp.simd = false;
	} else if (p_arg == "--max-speed") {
		if (!p_cursor.non_negative_number(&r_slam->max_speed_m_s)) {
			return usage("--max-speed needs a speed in m/s >= 0 (0: no limit)");
		}
	} else if (p_arg == "--noise-reference-m") {
		if (!p_cursor.non_negative_number(&r_slam->icp.depth_noise.reference_m)) {
			return usage("--noise-reference-m needs a depth in metres >= 0 (0: every reading weighs 1)");
		}
		if (r_slam->icp.depth_noise.reference_m == 0.0) {
			r_slam->icp.depth_noise.b_per_m2 = 0.0;
		}
	} else if (p_arg == "--colour-weight") {
		if (!p_cursor.non_negative_number(&r_slam->icp.colour_weight)) {
			return usage("--colour-weight needs a number >= 0 (metres per unit intensity; 0: geometry only)");
		}
	} else if (p_arg == "--icp-depth-range" || p_arg == "--tsdf-depth-range") {
		double range[2];
		if (!p_cursor.number_list(2, range) || !(range[0] >= 0.0) || !(range[1] > range[0])) {
			return usage((p_arg + " needs MIN,MAX in metres, 0 <= MIN < MAX").c_str());
		}
		if (p_arg == "--icp-depth-range") {
			r_slam->icp.min_depth_m = range[0];
			r_slam->icp.max_depth_m = range[1];
		} else {
			r_slam->tsdf.min_depth_m = float(range[0]);
			r_slam->tsdf.max_depth_m = float(range[1]);
		}
	} else if (p_arg == "--max-jump") {
		double jump[2];
		if (!p_cursor.number_list(2, jump) || !(jump[0] > 0.0) || !(jump[1] > 0.0)) {
			return usage("--max-jump needs M,DEG, both > 0 (metres and degrees)");
		}
		r_slam->icp.max_jump_m = jump[0];
		r_slam->icp.max_jump_deg = jump[1];
	} else if (p_arg == "--colour-slide") {
		double slide[2];
		if (!p_cursor.number_list(2, slide) || !(slide[0] >= 0.0) || !(slide[1] >= 0.0)) {
			return usage("--colour-slide needs M,DEG, both >= 0 (metres and degrees; 0,0: no guard)");
		}
		r_slam->icp.max_colour_slide_m = slide[0];
		r_slam->icp.max_colour_slide_deg = slide[1];
	} else if (p_arg == "--min-constraint") {
		if (!p_cursor.number_in(0.0, 1.0, &r_slam->icp.min_constraint)) {
			return usage("--min-constraint needs a share of the information in [0, 1]");
		}
	} else if (p_arg == "--raycast-level" || p_arg == "--finest-stride") {
		double v = 0.0;
		const bool level = p_arg == "--raycast-level";
		if (!p_cursor.number_in(level ? 0.0 : 1.0, level ? 3.0 : 4.0, &v) || v != double(int(v))) {
			return usage(level ? "--raycast-level needs a whole number in [0, 3]" : "--finest-stride needs a whole number in [1, 4]");
		}
		(level ? r_slam->raycast_level : r_slam->icp.finest_stride_px) = int(v);
	} else {
		return NOT_MINE;
	}
	return TAKEN;
}

// The options together: TAKEN when they can run, else usage's status.
int check_arguments(const Arguments &p_args) {
	if ((p_args.mode == "live" || p_args.mode == "soak") && p_args.recording.empty()) {
		return usage((p_args.mode + " needs --recording").c_str());
	}
	const int sources = int(!p_args.recording.empty()) + int(!p_args.tum.empty()) + int(!p_args.seven_scenes.empty());
	if (sources == 0) {
		return usage("--recording, --tum or --7scenes is required");
	}
	if (sources > 1) {
		// A benchmark ends with one summary line, of one source.
		return usage("--recording, --tum and --7scenes each name a source: give one");
	}
	if (!p_args.rig_file.empty() && p_args.has_intrinsics) {
		return usage("--rig and --intrinsics both give the RGB-D camera: take one");
	}
	if (!p_args.open3d_results.empty()) {
		// Checked now, not after the benchmark: a device there (/dev/zero) was read without end.
		if (p_args.recording.empty()) {
			return usage("--open3d-results compares Open3D on a recording's frames: it goes with --recording (with --tum or --7scenes it was ignored)");
		}
		const std::string unreadable = input_file_problem(p_args.open3d_results);
		if (!unreadable.empty()) {
			return usage(("--open3d-results " + unreadable).c_str());
		}
	}
	// Each bound holds alone; together they must fit too (issue #38: 64 probes of 4096^2 ran with no
	// progress). A probe keeps its faces and their mips as floats and half floats, about 40 bytes
	// a texel of the six faces.
	const double probe_bytes = double(std::max(1, p_args.probes)) * 6.0 * 40.0 * std::pow(double(p_args.probe_size > 0 ? p_args.probe_size : 256), 2.0);
	if (probe_bytes > MAX_PROBE_BYTES) {
		char text[200];
		std::snprintf(text, sizeof(text), "--probes %d x --probe-size %d need about %.1f GiB of maps, more than %.0f GiB: fewer probes or smaller faces",
				std::max(1, p_args.probes), p_args.probe_size, probe_bytes / 1073741824.0, MAX_PROBE_BYTES / 1073741824.0);
		return usage(text);
	}
	const std::string unwritable = save_trajectory_problem(p_args);
	return unwritable.empty() ? TAKEN : usage(unwritable.c_str());
}

} // namespace

void print_usage(std::FILE *p_out) {
	std::fprintf(p_out,
			"usage: roomprobe_bench slam (--recording DIR | --tum DIR | --7scenes DIR) [--frames N] [--threads N] [--probe-size N]\n"
			"                            [--intrinsics FX,FY,CX,CY | --rig FILE] [--save-trajectory FILE [--force]] [SLAM settings]\n"
			"       roomprobe_bench live --recording DIR [--speed X] [--frames N] [--threads N] [--probe-size N]\n"
			"                            [--intrinsics FX,FY,CX,CY | --rig FILE] [SLAM settings]\n"
			"       roomprobe_bench soak --recording DIR [--frames N] [--warmup-frames N] [--threads N] [--probe-size N] [SLAM settings]\n"
			"       roomprobe_bench decode --recording DIR [--frames N] [--repeats K] [--levels L1,L2,...] [--threads N]\n"
			"  slam --recording DIR  a RoomProbe recording through the engine (LiveRoom) in step mode: SLAM, coarse model,\n"
			"                        one probe's map after every RGB-D frame; per-stage timings, full frame, ATE, RPE. A SLAM-only\n"
			"                        recording (no room.yaml or no fisheye stream) runs dense SLAM alone, saying what it skips\n"
			"  slam --tum DIR        a TUM RGB-D sequence (rgb.txt, depth.txt, groundtruth.txt): dense SLAM alone\n"
			"  slam --7scenes DIR    a 7-Scenes-layout folder (frame-NNNNNN.color.jpg, .depth.png in mm, .pose.txt,\n"
			"                        camera-intrinsics.txt; frames at 30 Hz): dense SLAM alone\n"
			"  soak --recording DIR  the recording played back and forth through the engine in step mode, every stage and\n"
			"                        a probe, for --frames RGB-D frames (default 50000): resident memory flat within 5 %% after\n"
			"                        the warm-up (--warmup-frames N, default a fifth) and no growth in the time per frame, or status 1\n"
			"  live --recording DIR  the recording played in real time into the threaded engine (start()), the probe map\n"
			"                        polled at 60 Hz like Godot's main loop; frames dropped, latency, ATE\n"
			"  decode --recording DIR  reading each frame as stored (RecordingReader: milliseconds and bytes per frame), then\n"
			"                        every frame through PNG and zstd raw frames at --levels (default 1,2,3) in memory: encode\n"
			"                        and decode milliseconds, bytes, bit-exactness; --frames N per stream, --repeats K passes (default 3)\n"
			"  --frames N            stop after N RGB-D frames, 1 to 10000000 (default: all)\n"
			"  --threads N           worker threads for OpenCV and TBB, 1 to 1024 (default: the libraries')\n"
			"  --probe-size N        the probe's cubemap face size (default: slam %d, live %d)\n"
			"  --backend B           where the kernels with a GPU twin (tracking, fusion, raycasts, GGX, SH) run: cpu\n"
			"                        (default), vulkan, auto; the summary's backend key says where they ran\n"
			"  --speed X             live: playback speed, 0.01 to 1000 (default 1: real time)\n"
			"  --intrinsics FX,FY,CX,CY  the RGB-D camera's pinhole intrinsics, pixels, no distortion, instead of the source's\n"
			"                        (TUM: the freiburg set its folder names, else ROS's default; 7-Scenes: camera-intrinsics.txt)\n"
			"  --rig FILE            the RGB-D camera (rgb: intrinsics, distortion, size) of a rig file (calib/README.md)\n"
			"                        instead of the source's; the depth scale and any fisheye stay the source's\n"
			"  --save-trajectory FILE  slam: the tracked poses in TUM format (timestamp tx ty tz qx qy qz qw), one line per frame\n"
			"                        tracked good or poor; lost frames (no pose known) and poor ones' reasons as '#' comments;\n"
			"                        never inside an input; an existing FILE is kept unless --force\n"
			"  --probes N            slam --recording: render N probes every frame, the first at the probe, the others on a\n"
			"                        ring of 0.6 m around it (default 1); 'render_probes' times them all\n"
			"  --no-peers            slam --recording: skip the peers (OpenCV contrib's HASHTSDF volume integrating and raycasting\n"
			"                        the fused frames at the tracked poses, cv::rgbd::ICPOdometry frame to frame), run after the\n"
			"                        engine; their medians over ours are the summary's opencv_*_ratio keys\n"
			"  --open3d-results FILE slam --recording: Open3D VoxelBlockGrid's medians on the same frames (tools/bench/open3d_peer.py\n"
			"                        --out FILE; ./roomprobe bench ... --open3d runs it first); adds open3d_*_ratio to the summary\n"
			"SLAM settings (DenseSlamOptions; the effective ones are printed first):\n"
			"  --voxel-size-m V      TSDF voxel edge, metres, 0.001 to 0.02 (default %.3f)\n"
			"  --colour-weight W     ICP's photometric term, metres per unit intensity; 0: geometry only (default %.2f)\n"
			"  --icp-depth-range MIN,MAX   depth readings ICP uses, metres along z (default %.2f,%.2f)\n"
			"  --tsdf-depth-range MIN,MAX  depth readings fused into the TSDF, metres along z (default %.2f,%.2f)\n"
			"  --max-jump M,DEG      largest move from the predicted pose believed per frame, metres and degrees (default %.2f,%.0f)\n"
			"  --colour-slide M,DEG  largest move of the colour term along a direction the geometry leaves free believed per\n"
			"                        frame, from the predicted pose (beyond: kept at the prediction, Poor), e.g. 0.015,1.5;\n"
			"                        0,0: no guard (default %.3f,%.1f)\n"
			"  --max-speed M_S       a pose moved faster than this since the last tracked one (+ 2 cm) is Lost; 0: off\n"
			"                        (default %.1f m/s)\n"
			"  --colour-always       the photometric term at every level, not only where the geometry leaves a direction free\n"
			"  --scalar-icp          ICP's point-to-plane rows one pixel at a time, not eight at once with AVX2 (the CPU's)\n"
			"  --min-constraint C    a direction with less than this share of the geometry's information is free (default 0.004)\n"
			"  --raycast-level L     the tracking reference raycast at 1 / 2^L of the camera's size, 0 to 3 (default 2)\n"
			"  --points-normals      the reference's normals from its neighbouring points, not the tsdf's gradient at each hit\n"
			"  --young-model N,K     while fewer than N frames are fused, a free direction needs K x the reference normals' spread\n"
			"                        of the information (default 0,0.25: off; measured at 15,0.25)\n"
			"  --finest-stride S     ICP's finest level pairs every S-th pixel of every S-th row, 1 to 4 (default 2)\n"
			"  --noise-reference-m R ICP weighs a depth reading by its noise relative to one at R metres (nearer ones weigh 1);\n"
			"                        0: all readings weigh 1 (default %.2f)\n"
			"Targets are printed only for synthetic recordings (synth.yaml). Each benchmark ends with one line\n"
			"'summary: mode=... key=value ...'.\n",
			STEP_PROBE_SIZE, LIVE_PROBE_SIZE, double(TsdfOptions().voxel_size_m), DenseSlamOptions().icp.colour_weight, DenseSlamOptions().icp.min_depth_m,
			DenseSlamOptions().icp.max_depth_m, double(TsdfOptions().min_depth_m), double(TsdfOptions().max_depth_m), DenseSlamOptions().icp.max_jump_m,
			DenseSlamOptions().icp.max_jump_deg, DenseSlamOptions().icp.max_colour_slide_m, DenseSlamOptions().icp.max_colour_slide_deg,
			DenseSlamOptions().max_speed_m_s, DenseSlamOptions().icp.depth_noise.reference_m);
}

int usage(const char *p_error) {
	if (p_error != nullptr) {
		std::fprintf(stderr, "roomprobe_bench: %s\n", p_error);
	}
	print_usage(stderr);
	return 2;
}

int parse_arguments(int p_argc, char **p_argv, Arguments *r_args) {
	cli::Arguments cursor(p_argc, p_argv, 2);
	std::string arg;
	while (cursor.next(&arg)) {
		if (arg == "--help" || arg == "-h") {
			print_usage(stdout);
			return 0;
		}
		int status = source_option(cursor, arg, r_args);
		status = status == NOT_MINE ? run_option(cursor, arg, r_args) : status;
		status = status == NOT_MINE ? slam_option(cursor, arg, &r_args->slam) : status;
		if (status == NOT_MINE) {
			return usage(("unknown argument " + arg + " for " + r_args->mode).c_str());
		}
		if (status != TAKEN) {
			return status;
		}
	}
	const int checked = check_arguments(*r_args);
	return checked == TAKEN ? -1 : checked;
}

int run_decode(int p_argc, char **p_argv) {
	DecodeBenchOptions options;
	cli::Arguments cursor(p_argc, p_argv, 2);
	std::string arg;
	while (cursor.next(&arg)) {
		int status = TAKEN;
		if (arg == "--recording") {
			status = text_option(cursor, "--recording needs a folder", &options.recording);
		} else if (arg == "--frames") {
			status = frames_option(cursor, &options.frames);
		} else if (arg == "--repeats") {
			status = integer_option(cursor, 1, 1000, "--repeats needs a number of passes, 1 to 1000", &options.repeats);
		} else if (arg == "--levels") {
			std::string text;
			std::vector<double> levels;
			if (!cursor.value(&text) || !cli::parse_number_list(text, &levels) || levels.empty() || levels.size() > 16 ||
					std::any_of(levels.begin(), levels.end(), [](double p_level) { return p_level != std::floor(p_level) || p_level < -7 || p_level > 22; })) {
				return usage("--levels needs 1 to 16 zstd levels, whole numbers in [-7, 22], comma-separated (e.g. 1,2,3)");
			}
			options.levels.assign(levels.begin(), levels.end());
		} else if (arg == "--threads") {
			int threads = 0;
			status = threads_option(cursor, &threads);
			if (status == TAKEN) {
				cv::setNumThreads(threads);
			}
		} else if (arg == "--help" || arg == "-h") {
			print_usage(stdout);
			return 0;
		} else {
			return usage(("unknown argument " + arg + " for decode").c_str());
		}
		if (status != TAKEN) {
			return status;
		}
	}
	if (options.recording.empty()) {
		return usage("decode needs --recording");
	}
	return bench_decode(options);
}

} // namespace roomprobe::bench
