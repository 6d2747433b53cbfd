#pragma once
// Reads a folder of numbered RGB-D frames in the layout of Microsoft's 7-Scenes (also 3DMatch's
// and andyzeng's tsdf-fusion samples of SUN3D) as an RGB-D-only recording:
//   frame-NNNNNN.color.jpg (or .color.png)  8-bit colour
//   frame-NNNNNN.depth.png                  16-bit depth, options' units (7-Scenes: millimetres),
//                                           0 = no reading (7-Scenes' 65535 lies beyond any
//                                           depth range SLAM uses)
//   frame-NNNNNN.pose.txt                   4x4 world_from_camera, row-major, metres (optional)
//   camera-intrinsics.txt                   3x3 K, row-major (fx 0 cx / 0 fy cy / 0 0 1)
// The files give no timestamps: frame N plays at N / frame_rate_hz seconds, so a gap in the
// numbering keeps its time. The poses become the ground-truth RGB-D trajectory, at the same
// timestamps. In 7-Scenes colour is not registered to depth (the images are offset by a few
// pixels): the reader pairs them as they are and says nothing of it. The dataset has no room
// (has_room() is false), no fisheye frames, and its world frame is the dataset's.

#include "recording_reader.h"

#include <camera/camera_params.h>

#include <string>

namespace roomprobe {

struct FramesDatasetOptions {
	// When set (fx, fy > 0), used instead of camera-intrinsics.txt, which may then be missing.
	// Width and height 0: the depth images' size.
	bool override_intrinsics = false;
	PinholeParams intrinsics;
	double depth_scale_m = 0.001; // metres per depth unit (7-Scenes: millimetres)
	double frame_rate_hz = 30.0; // frame N is at N / frame_rate_hz seconds (7-Scenes: about 30 Hz)
};

// Opens the frames in p_folder into r_reader, which then plays them like a recording (rig: the
// intrinsics, depth_scale_m, no fisheye). Fails, naming the file, when the folder is missing,
// holds no frame-NNNNNN.depth.png, camera-intrinsics.txt is missing (and not overridden) or not
// a 3x3 pinhole K, or the options are unusable. Issues, each naming the file: a gap in the
// numbering (one issue per gap), a frame without its colour or depth image, images that are
// missing, cut short or of the wrong size or type, and a pose file that is not a 4x4 rigid
// transform with a last row 0 0 0 1 (that frame has no ground-truth pose; the others do).
RecordingStatus open_frames_dataset(const std::string &p_folder, RecordingReader *r_reader, const FramesDatasetOptions &p_options = FramesDatasetOptions());

} // namespace roomprobe
