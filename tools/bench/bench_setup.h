#pragma once
// What a benchmark plays: a RoomProbe recording opened into a RecordingPlayer with the engine's
// configuration (config_from_recording, then the bench's own settings), or, for dense SLAM alone,
// a DenseSource (a TUM sequence, a 7-Scenes-layout folder or a SLAM-only recording).

#include "bench_common.h"

#include <source/recording_player.h>

#include <memory>
#include <string>

namespace roomprobe::bench {

// The RGB-D camera --rig or --intrinsics gives on top of p_base, the source's own (--intrinsics
// keeps its size, drops its distortion). Unchanged, with an empty note, when neither is given.
// False after printing the problem.
bool camera_from_arguments(const Arguments &p_args, const PinholeParams &p_base, PinholeParams *r_camera, std::string *r_note);

// A recording opened, with the engine's configuration as the Godot nodes build it.
struct RecordingSetup {
	RecordingPlayer player; // the events to play (--frames RGB-D frames) and the reader
	LiveRoomConfig config;
	glm::dvec3 probe = glm::dvec3(0.0);
	bool probe_from_file = false;
	int probe_size = 0; // its map's face size (--probe-size, else the benchmark's default)
	bool synthetic = false; // made by ./roomprobe synth (synth.yaml): the targets apply
	PinholeParams camera; // the RGB-D camera SLAM uses (the rig's, or --rig's or --intrinsics')
	std::string camera_note; // where it comes from when not the rig ("--intrinsics")
	// Why the engine cannot run (no room, no fisheye stream): dense SLAM alone then. Empty: it can.
	std::string engine_skip;

	const RecordingReader &reader() const { return player.reader(); }
	size_t rgbd_total() const { return player.rgbd_events(); } // RGB-D frames to play
};

// Opens p_args.recording and builds the configuration, the probe's map p_default_probe_size
// unless --probe-size; false after printing the problem.
bool open_recording(const Arguments &p_args, int p_default_probe_size, RecordingSetup *r_setup);
// Configures r_engine from p_setup; false after printing the problem, p_what naming the run.
bool configure_engine(const RecordingSetup &p_setup, const std::string &p_what, LiveRoom *r_engine);
// p_engine: configured from p_setup (it says where the GPU-capable kernels run).
void print_recording_header(const char *p_mode, const Arguments &p_args, const RecordingSetup &p_setup, const LiveRoom &p_engine);

// What dense SLAM alone runs on: a TUM sequence, a 7-Scenes-layout folder or a SLAM-only recording.
struct DenseSource {
	const char *mode = ""; // the summary's mode: tum, 7scenes, recording
	std::string option; // "--tum DIR", for messages
	std::shared_ptr<const RecordingReader> reader;
	PinholeParams camera; // the RGB-D camera SLAM uses
	std::string camera_note; // where it comes from
	bool synthetic = false; // the targets apply
	bool has_start_pose = false; // room.yaml's initial pose at frame 0; else the ground truth's first
	Pose start_pose;
	std::string skipped; // what is not run and why ("no fisheye stream: ...")
};

int bench_dense(const Arguments &p_args, const DenseSource &p_source);

} // namespace roomprobe::bench
