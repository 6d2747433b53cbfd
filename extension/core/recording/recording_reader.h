#pragma once
// Reads a RoomProbe recording (docs/recording-format.md) for playback: the rig, the room, both
// frame indexes, ground truth, and the frames themselves on demand.
//
// Opening is forgiving where it can be: a frame whose line does not parse, whose timestamp goes
// backwards, whose image is missing, cut short or of the wrong size or type, or that has no
// partner within the association window, is listed in get_issues() (file and line) and left
// out; the rest plays on. Only an unusable rig.yaml, room.yaml or frame index fails open().
// A recording may be SLAM-only: no room.yaml (has_room() false) and a rig without a fisheye
// (then no fisheye.txt either).
// Reading a frame re-checks its images and returns an error naming the image file, so that a
// file that goes bad after open() is one lost frame, not a crash.
//
// After open(), every const method may be called from several threads at once.

#include "recording_types.h"

#include <rig/rig.h>
#include <rig/trajectory.h>

#include <map>
#include <string>
#include <vector>

namespace roomprobe {

// An RGB-D frame of the index: an RGB image and the depth image associated with it.
struct RgbdFrameRef {
	FrameRef rgb; // from rgb.txt
	FrameRef depth; // from depth.txt
};

// What open() reads from a folder before any image is decoded. Other dataset readers
// (tum_dataset.h) fill one in and hand it to RecordingReader::open_contents().
struct RecordingContents {
	std::string folder; // frame paths are relative to it
	Rig rig;
	bool has_room = false; // false for datasets without a room (TUM)
	RoomInfo room;
	std::vector<RgbdFrameRef> rgbd; // strictly increasing rgb timestamps
	std::vector<FrameRef> fisheye; // strictly increasing timestamps, fisheye clock
	bool has_ground_truth[2] = { false, false }; // indexed by RecordingStream
	Trajectory ground_truth[2]; // world_from_camera, each on its own camera's clock
	std::vector<CubemapRef> cubemaps; // non-decreasing timestamps, RGB-D clock
	// capture.txt (live recordings): what the devices said about each frame, by RecordingStream,
	// keyed by the frame's timestamp (the RGB timestamp for RGB-D frames).
	std::map<double, CaptureInfo> capture[2];
	std::vector<RecordingIssue> issues;
};

struct RecordingReadOptions {
	// An RGB image and a depth image pair up when their timestamps are closer than this (TUM's
	// associate.py default). A recording written by RecordingWriter gives both the same timestamp.
	double max_rgb_depth_difference_s = 0.02;
};

class RecordingReader {
public:
	RecordingReader() = default;
	RecordingReader(const RecordingReader &) = delete;
	RecordingReader &operator=(const RecordingReader &) = delete;

	// Reads p_folder's rig.yaml, room.yaml, rgb.txt, depth.txt, fisheye.txt and any ground truth.
	// Fails (error naming the file and field or line) only when rig.yaml or one of the indexes is
	// missing or unusable, or room.yaml is there but unusable; problems with single frames are
	// issues. A missing room.yaml means no room; fisheye.txt may be missing when the rig has no
	// fisheye (frames listed in one are then an issue and left out).
	RecordingStatus open(const std::string &p_folder, const RecordingReadOptions &p_options = RecordingReadOptions());
	// Plays contents read by some other reader (e.g. open_tum_dataset()). Builds the event list.
	void open_contents(RecordingContents p_contents);
	void close();
	bool is_open() const { return opened; }

	const std::string &get_folder() const { return contents.folder; }
	const Rig &get_rig() const { return contents.rig; }
	bool has_room() const { return contents.has_room; }
	const RoomInfo &get_room() const { return contents.room; }
	// Non-fatal problems found by open(), in the order found.
	const std::vector<RecordingIssue> &get_issues() const { return contents.issues; }

	size_t rgbd_count() const { return contents.rgbd.size(); }
	size_t fisheye_count() const { return contents.fisheye.size(); }
	const RgbdFrameRef &get_rgbd_ref(size_t p_index) const { return contents.rgbd[p_index]; }
	const FrameRef &get_fisheye_ref(size_t p_index) const { return contents.fisheye[p_index]; }

	// Decodes RGB-D frame p_index (0 <= p_index < rgbd_count()): rgb (a PNG, or a JPEG for
	// datasets that store colour so) CV_8UC3 in R, G, B order,
	// depth_m CV_32FC1 metres with NaN for no reading. The error names the image file: missing,
	// truncated, corrupt, wrong size for the rig, wrong type.
	RgbdFrameResult read_rgbd(size_t p_index) const;
	// Decodes fisheye frame p_index: CV_8UC1 or CV_8UC3 (R, G, B) from a PNG, CV_32FC3 linear
	// R, G, B from an EXR (hdr true). The timestamp is on the fisheye's clock.
	FisheyeFrameResult read_fisheye(size_t p_index) const;

	// Frames of both streams in time order on the RGB-D clock (fisheye timestamps plus
	// Rig::fisheye_time_offset_s); at equal times the RGB-D frame comes first.
	const std::vector<PlaybackEvent> &get_events() const { return events; }

	bool has_ground_truth_trajectory(RecordingStream p_stream) const { return contents.has_ground_truth[int(p_stream)]; }
	// world_from_camera of that stream's camera, on that camera's clock; empty when there is none.
	const Trajectory &ground_truth_trajectory(RecordingStream p_stream) const { return contents.ground_truth[int(p_stream)]; }

	size_t ground_truth_cubemap_count() const { return contents.cubemaps.size(); }
	const CubemapRef &get_ground_truth_cubemap_ref(size_t p_index) const { return contents.cubemaps[p_index]; }
	// Reads ground-truth cubemap p_index: six CV_32FC3 faces from the EXR strip, and the 8-bit
	// view when a PNG of the same name lies next to it.
	GroundTruthCubemapResult ground_truth_cubemap(size_t p_index) const;

private:
	void build_events();

	bool opened = false;
	RecordingContents contents;
	std::vector<PlaybackEvent> events;
};

namespace recording_io {

// Shared by RecordingReader::open() and open_tum_dataset(): pairs rgb with depth frames
// (associate()), checks that each pair's images exist and have the rig's size and type (from
// their PNG headers), and appends the good pairs to r_contents->rgbd. Unpaired frames are
// issues, one each, or, with p_summarise_unpaired, one issue per index giving the count.
void pair_and_check_rgbd(const std::vector<FrameRef> &p_rgb, const std::string &p_rgb_index, const std::vector<FrameRef> &p_depth,
		const std::string &p_depth_index, double p_max_difference_s, bool p_summarise_unpaired, RecordingContents *r_contents);

} // namespace recording_io

} // namespace roomprobe
