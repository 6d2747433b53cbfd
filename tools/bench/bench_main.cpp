// roomprobe_bench: where the time of a live frame goes, and how accurate tracking is. Every
// recording benchmark drives one LiveRoom (engine/live_room.h), the engine the Godot nodes and
// roomprobe_eval drive, so what is measured is what ships.
//
// slam --recording DIR: the engine in step mode (no threads) over a RoomProbe recording, every
// event in time order, configured as the nodes configure it (the recording's rig and photometry,
// the room's floorplan and initial pose, the probes as the TSDF's keep points, tracked poses for
// both models, async inpainting, gain lighting compensation, a re-mesh every 15 fused frames) with
// one probe at probe 0 (--probe-size, default 128):
//   RGB-D frame:   push_rgbd (DenseSlam; every 15 fused frames the dense mesh), then render_probes
//                  (coarse cubemap, the dense pass over it, SH, the half-float mip chains);
//   fisheye frame: push_fisheye (its pose from the TRACKED trajectory, then the coarse pipeline).
// Prints per-stage median, mean and p90 against the paper's Table 1 (from the engine's published
// timings: TrackedFrame, CoarseSnapshot, ProbeMap), the whole engine calls, the full frame, the
// dense pass's cost at three raycast scales and two sizes on the final model, ATE against the
// ground truth, and the TSDF's memory. Reading and decoding the images is not timed.
//
// A recording without a room (no room.yaml) or without a fisheye stream is SLAM-only: slam runs
// dense SLAM alone on it (as below) and says what it skips; live refuses it.
//
// slam --tum DIR, slam --7scenes DIR: dense SLAM alone (DenseSlam: the engine needs a rig with a
// fisheye, which datasets have not) on a TUM RGB-D sequence or a 7-Scenes-layout folder of frames
// (recording/frames_dataset.h), from the ground-truth pose of the first frame that has one; the
// same timings, ATE and RPE, and the time per frame.
//
// Accuracy (eval/trajectory_metrics.h): ATE and RPE (per frame and per second) of every processed
// frame's reported pose (the held one when Lost) against the ground truth, no alignment (SLAM
// starts in the ground truth's world frame). The targets (TARGET ...) are printed for synthetic
// recordings only (those with synth.yaml, made by ./roomprobe synth), never for real data.
// --save-trajectory FILE writes the tracked poses in TUM's format (TumTrajectoryWriter): one line
// per frame tracked Good or Poor; a Lost frame, whose pose is not known, is a '#' comment with
// its reason, as is a Poor frame's reason before its line. FILE must lie outside the inputs, and
// an existing one is kept unless --force.
//
// SLAM settings (--voxel-size-m, --colour-weight, --colour-always, --icp-depth-range, --tsdf-depth-range, --noise-reference-m,
// --max-jump, --max-speed) change DenseSlamOptions for every mode; --intrinsics or --rig replace the RGB-D
// camera's intrinsics. The effective settings are printed first.
//
// live --recording DIR: the engine threaded (start()), the recording played in real time (x
// --speed) by a PacedPlayer (source/paced_player.h) whose thread reads and decodes each frame at
// its event's instant (capture time, not the engine's) and pushes it; the main thread polls the probe map at 60 Hz as
// Godot's main loop would and copies its GPU bytes. At the end finish() and stop(); prints what
// was pushed, processed and dropped per stream, the latency from a frame's push to the first probe
// map that includes it, the probe renders, the real-time factor, the tracking states and ATE.
//
// decode --recording DIR: what reading the recording's frames costs, and each frame encoding (PNG,
// zstd raw frames) on the same frames (bench_decode.h).
//
// Each benchmark ends with one line 'summary: mode=... key=value ...'. Prints figures; asserts
// nothing (the targets are reported as met or not).
//
// Every benchmark plays its frames through a RecordingPlayer (source/recording_player.h) and takes
// the engine's configuration from config_from_recording (engine/engine_config.h). The files:
// bench_args.cpp (the command line), bench_common (series, rows, SLAM figures, accuracy),
// bench_setup (a recording opened, the dense-only source), bench_recording.cpp (slam --recording),
// bench_speed (issue #11's targets and peers), bench_live.cpp, bench_soak.cpp, bench_dense.cpp
// (--tum, --7scenes, SLAM-only recordings), bench_decode.cpp.
//
// usage: roomprobe_bench slam (--recording DIR | --tum DIR | --7scenes DIR) [--frames N] [--threads N] [--probe-size N]
//                             [--intrinsics FX,FY,CX,CY | --rig FILE] [--save-trajectory FILE [--force]] [--voxel-size-m V]
//                             [--colour-weight W] [--icp-depth-range MIN,MAX] [--tsdf-depth-range MIN,MAX] [--max-jump M,DEG]
//                             [--max-speed M_S]
//        roomprobe_bench live --recording DIR [--speed X] [--frames N] [--threads N] [--probe-size N] [the same camera and SLAM options]
//        roomprobe_bench soak --recording DIR [--frames N] [--threads N] [--probe-size N] [the same camera and SLAM options]
//        roomprobe_bench decode --recording DIR [--frames N] [--repeats K] [--levels L1,L2,...] [--threads N]

#include "bench_common.h"

#include "../common/cli.h"

#include <io/opencv.h>

#include <tbb/global_control.h>

#include <memory>
#include <string>

namespace roomprobe::bench {

namespace {

int run(int argc, char **argv) {
	if (argc < 2) {
		return usage(nullptr);
	}
	const std::string verb = argv[1];
	if (verb == "--help" || verb == "-h") {
		print_usage(stdout);
		return 0;
	}
	if (verb != "slam" && verb != "live" && verb != "soak" && verb != "decode") {
		return usage(("unknown benchmark '" + verb + "' (slam, live, soak or decode)").c_str());
	}
	if (verb == "decode") {
		return run_decode(argc, argv);
	}
	Arguments args;
	args.mode = verb;
	const int parsed = parse_arguments(argc, argv, &args);
	if (parsed >= 0) {
		return parsed;
	}
	// OpenCV's parallel_for_ (SLAM kernels) and TBB (coarse model, cubemaps) each have a pool.
	std::unique_ptr<tbb::global_control> tbb_threads;
	if (args.threads > 0) {
		cv::setNumThreads(args.threads);
		tbb_threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(args.threads));
	}
	if (args.mode == "live") {
		return bench_live(args);
	}
	if (args.mode == "soak") {
		return bench_soak(args);
	}
	if (!args.recording.empty()) {
		return bench_recording(args);
	}
	if (!args.tum.empty()) {
		return bench_tum(args);
	}
	return bench_7scenes(args);
}

} // namespace

} // namespace roomprobe::bench

int main(int argc, char **argv) {
	return roomprobe::cli::guarded_main("roomprobe_bench", [&] { return roomprobe::bench::run(argc, argv); });
}
