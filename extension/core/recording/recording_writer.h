#pragma once
// Writes a RoomProbe recording (docs/recording-format.md): rig.yaml and room.yaml at open(),
// each frame's images as it is added (with its index line, flushed, so that a recording cut off
// by a crash still reads up to its last frame), ground-truth trajectories at close().
//
// Every call returns a status whose error names the file (and what is wrong); a failed call
// writes no index line, so the recording stays readable. Not thread-safe: one thread writes.

#include "recording_types.h"

#include <io/raw_frame.h>
#include <rig/rig.h>
#include <rig/trajectory.h>

#include <fstream>
#include <string>

namespace roomprobe {

// How the writer stores RGB, depth and 8-bit fisheye frames (docs/recording-format.md, "Images").
enum class FrameFormat {
	Zstd, // raw frame files, NNNNNN.zst (io/raw_frame.h): the samples compressed by zstd; decode about ten times faster than PNG
	Png, // PNG files, NNNNNN.png (zlib level 1): the format of recordings made before raw frames; image viewers open them
};
// "zstd" or "png".
const char *frame_format_name(FrameFormat p_format);
// "zstd" or "png" (as the tools' --frame-format takes it); false for anything else.
bool parse_frame_format(const std::string &p_text, FrameFormat *r_format);

struct RecordingWriteOptions {
	// open() refuses a folder that exists and holds anything, so no one's data is overwritten.
	// With this set it writes into such a folder, replacing files that have the recording's
	// names (rig.yaml, rgb/000000.zst, ...); other files are left as they are.
	bool allow_non_empty_folder = false;
	// EXR channels (HDR fisheye frames, ground-truth cubemaps) as 32-bit float rather than half.
	// Half keeps 11 significant bits and values up to 65504; larger values are an error with half.
	bool exr_full_float = false;
	// RGB, depth and 8-bit fisheye frames as raw frames (the default) or PNG. HDR fisheye frames and
	// ground-truth cubemaps are EXR either way.
	FrameFormat frame_format = FrameFormat::Zstd;
	// zstd's level for raw frames (ZSTD_minCLevel() to ZSTD_maxCLevel(); open() refuses others).
	int zstd_level = kRawFrameDefaultLevel;
};

class RecordingWriter {
public:
	RecordingWriter() = default;
	RecordingWriter(const RecordingWriter &) = delete;
	RecordingWriter &operator=(const RecordingWriter &) = delete;
	// Closes the recording (as close(), ignoring its errors).
	~RecordingWriter();

	// Creates p_folder (and its parents) if need be, writes rig.yaml and room.yaml, and starts
	// the three frame indexes (two when the rig has no fisheye: no fisheye.txt). The rig and room
	// must pass check_rig() and check_room(). One writer a folder: while open, the writer holds
	// recording_io::WRITING_MARKER in it, locked, and a second writer into that folder (another
	// process or thread) is refused, never mixing its frames with the first's (issue #38).
	RecordingStatus open(const std::string &p_folder, const Rig &p_rig, const RoomInfo &p_room,
			const RecordingWriteOptions &p_options = RecordingWriteOptions());
	// The same for a recording without a room (SLAM only): no room.yaml, and no ground-truth cubemaps.
	RecordingStatus open_without_room(const std::string &p_folder, const Rig &p_rig, const RecordingWriteOptions &p_options = RecordingWriteOptions());
	bool is_open() const { return opened; }

	// Writes rgb/NNNNNN.zst and depth/NNNNNN.zst (.png with FrameFormat::Png) and their index lines. rgb: CV_8UC3 R, G, B, the
	// rig's rgb size. depth_m: CV_32FC1 metres (NaN, infinite or <= 0: no reading; stored as
	// round(metres / depth_scale_m), an error when beyond 65535 units) or CV_16UC1 raw units, same
	// size. Timestamps must be finite and increase strictly within rgb.txt and within depth.txt.
	// A frame whose capture is known (a live frame) also gets its line in capture.txt.
	RecordingStatus add_rgbd(const RgbdFrame &p_frame);
	// Writes fisheye/NNNNNN.zst or .png (CV_8UC1 or CV_8UC3 R, G, B) or fisheye/NNNNNN.exr (CV_32FC3,
	// hdr set) and its index line; the rig's fisheye size; strictly increasing timestamps. An
	// error when the rig has no fisheye.
	RecordingStatus add_fisheye(const FisheyeFrame &p_frame);
	// Appends a ground-truth pose (world_from_camera) of one stream's camera at p_t_s on that
	// camera's clock; strictly increasing per stream. Written at close().
	RecordingStatus add_ground_truth_pose(RecordingStream p_stream, double p_t_s, const Pose &p_world_from_camera);
	// Writes groundtruth/cubemaps/NNNNNN.exr (the six CV_32FC3 N x N faces as an N x 6N strip,
	// cubemap_layout.h), with NNNNNN.png next to it when p_ldr_faces are given (six CV_8UC3
	// R, G, B faces of the same size; all empty for none), and its line in cubemaps.txt.
	// p_probe_index must be one of the room's probes (an error without a room); timestamps (RGB-D
	// clock) must not decrease.
	RecordingStatus add_ground_truth_cubemap(double p_t_s, int p_probe_index, const CubemapFaces &p_faces,
			const CubemapFaces &p_ldr_faces = CubemapFaces());

	// Writes the ground-truth trajectories and closes every file. The first error is returned;
	// the writer is closed either way. Closing a closed writer does nothing.
	RecordingStatus close();

	const std::string &get_folder() const { return folder; }
	size_t get_rgbd_count() const { return rgbd_count; }
	size_t get_fisheye_count() const { return fisheye_count; }
	// Bytes of the RGB, depth and fisheye image files written since open() (as on disk).
	uint64_t get_image_bytes() const { return image_bytes; }

private:
	RecordingStatus open_folder(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingWriteOptions &p_options);
	RecordingStatus fail(std::string p_error) const;
	std::string append_line(std::ofstream &p_index, const std::string &p_index_name, const std::string &p_line);
	std::string append_capture(RecordingStream p_stream, double p_timestamp_s, const CaptureInfo &p_capture);
	std::string path(const std::string &p_relative) const;

	bool opened = false;
	std::string folder;
	Rig rig;
	bool has_room = false;
	RoomInfo room;
	RecordingWriteOptions options;
	std::ofstream rgb_index;
	std::ofstream depth_index;
	std::ofstream fisheye_index;
	std::ofstream cubemap_index; // opened with the first cubemap
	std::ofstream capture_index; // opened with the first frame that carries CaptureInfo
	size_t rgbd_count = 0;
	size_t fisheye_count = 0;
	size_t cubemap_count = 0;
	uint64_t image_bytes = 0;
	bool has_rgb_time = false;
	double last_rgb_time_s = 0.0;
	double last_depth_time_s = 0.0;
	bool has_fisheye_time = false;
	double last_fisheye_time_s = 0.0;
	bool has_cubemap_time = false;
	double last_cubemap_time_s = 0.0;
	Trajectory ground_truth[2]; // indexed by RecordingStream
	int claim = -1; // WRITING_MARKER's descriptor, locked while open; -1 when none is held
	bool claim_made = false; // the marker was made by this writer (removed when the open fails)
	std::string claim_folder(const std::string &p_folder);
	void release_claim(bool p_remove);
};

} // namespace roomprobe
