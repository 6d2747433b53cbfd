#pragma once
// Plain data of RoomProbe recordings (docs/recording-format.md): the frames of the two
// unsynchronised streams (paper §3.2, §4.3), the room, ground truth, and the results and
// non-fatal issues of reading and writing. No Godot; copyable values only (cv::Mat copies share
// pixels: clone() before writing into a frame someone else holds).

#include <io/opencv.h>
#include <math/pose.h>
#include <types/cubemap_layout.h>
#include <types/frames.h>
#include <types/room_types.h>

#include <glm/vec3.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace roomprobe {

// The two streams of a recording. Each has its own frame index and its own clock: the RGB-D
// camera's, and the fisheye's (add Rig::fisheye_time_offset_s to get RGB-D clock time).
enum class RecordingStream {
	Rgbd,
	Fisheye,
};

// "rgbd" or "fisheye", for messages.
const char *recording_stream_name(RecordingStream p_stream);

// One line of a frame index (rgb.txt, depth.txt, fisheye.txt).
struct FrameRef {
	double timestamp_s = 0.0; // seconds, on the clock of the stream's camera
	std::string path; // as written in the index: relative to the recording folder, '/' separated
	int line = 0; // 1-based line of the index that lists it (0: not from a file)
};

// depth_m from 16-bit raw depth (CV_16UC1, units of p_scale_m, 0 or 65535 = no reading: sensors
// mark saturated or invalid pixels with either): CV_32FC1 metres, NaN where there is no reading. Recordings (depth PNGs) and live cameras (OpenNI2's millimetres)
// both come in this way.
cv::Mat depth_metres_from_raw(const cv::Mat &p_raw, double p_scale_m);

// What is wrong with a fisheye frame's image for a fisheye of p_width x p_height ("" when
// nothing): its type (CV_8UC1, CV_8UC3, or CV_32FC3 exactly when hdr), its size, and for HDR any
// NaN or infinite value, counted. The writer refuses such a frame and the engine does not
// integrate it (a wrong-sized image once textured the room with garbage, silently).
std::string check_fisheye_image(const FisheyeFrame &p_frame, int p_width, int p_height);

// The room of a recording (room.yaml).
struct RoomInfo {
	Floorplan floorplan; // metres, floor plane y = 0; Vec2::y is world z
	Pose initial_rgb_pose; // world_from_rgb at the first RGB-D frame (world: Y up, metres)
	std::vector<glm::dvec3> probes; // probe positions, world metres; GT cubemaps refer to these by index
};

// A problem found while reading that did not stop the reading: the frame, line or file named is
// skipped and the rest plays on.
struct RecordingIssue {
	std::string file; // the file the problem is in (an index, a YAML file, an image), as a path
	int line = 0; // 1-based line in file, or 0 where there is none
	std::string message; // what is wrong and what was done about it, naming any image involved
};

// "file:line: message" (or "file: message" without a line).
std::string to_string(const RecordingIssue &p_issue);
// Every issue as to_string gives it, each once, in the order first met: what a tool lists.
std::vector<std::string> issue_lines(const std::vector<RecordingIssue> &p_issues);

// One line of groundtruth/cubemaps.txt.
struct CubemapRef {
	double timestamp_s = 0.0; // seconds on the RGB-D clock
	int probe_index = 0; // into RoomInfo::probes
	std::string path; // the EXR, relative to the recording folder
	int line = 0; // 1-based line in cubemaps.txt
};

// A ground-truth environment map at one probe and instant.
struct GroundTruthCubemap {
	double timestamp_s = 0.0; // seconds on the RGB-D clock
	int probe_index = 0; // into RoomInfo::probes
	glm::dvec3 position = glm::dvec3(0.0); // RoomInfo::probes[probe_index], world metres
	CubemapFaces faces; // CV_32FC3 linear R, G, B (radiance, the renderer's units)
	CubemapFaces ldr_faces; // CV_8UC3 R, G, B (the 8-bit view), or all empty when none was stored
};

// One event of playback: the next frame of one stream, in time order across both.
struct PlaybackEvent {
	RecordingStream stream = RecordingStream::Rgbd;
	size_t index = 0; // frame index in that stream: read_rgbd(index) or read_fisheye(index)
	double time_s = 0.0; // on the RGB-D clock (fisheye timestamp + Rig::fisheye_time_offset_s)
};

// The outcome of an operation without a value.
struct RecordingStatus {
	bool ok = false;
	std::string error; // empty when ok; otherwise names the file (and field or line)
};

struct RgbdFrameResult {
	bool ok = false;
	std::string error; // names the image file: "rec/rgb/000003.png: missing"
	RgbdFrame frame;
};

struct FisheyeFrameResult {
	bool ok = false;
	std::string error; // names the image file
	FisheyeFrame frame;
};

struct GroundTruthCubemapResult {
	bool ok = false;
	std::string error; // names the EXR or PNG file
	GroundTruthCubemap cubemap;
};

} // namespace roomprobe
