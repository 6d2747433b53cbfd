#pragma once
// Reads a TUM RGB-D benchmark sequence (Sturm et al. 2012, cvg.cit.tum.de/data/datasets/rgbd-dataset)
// as an RGB-D-only recording: rgb.txt and depth.txt ('timestamp filename', '#' comments),
// rgb/*.png (640x480 8-bit RGB), depth/*.png (640x480 16-bit, 5000 units = 1 m, 0 = no data,
// registered to the RGB camera), groundtruth.txt ('timestamp tx ty tz qx qy qz qw', the colour
// camera's optical centre in the motion-capture world). RGB and depth frames are paired as
// TUM's associate.py pairs them. The sequence has no room (has_room() is false), no fisheye
// frames, and its world frame is the motion-capture system's, not RoomProbe's Y-up world.

#include "recording_reader.h"

#include <camera/camera_params.h>

#include <string>

namespace roomprobe {

// The RGB camera intrinsics TUM publishes (640x480). The files give no intrinsics, so the
// caller picks them; TUM recommends the ROS default set for the registered depth images.
enum class TumCamera {
	RosDefault, // fx = fy = 525, cx = 319.5, cy = 239.5, no distortion
	Freiburg1, // fx 517.306408, fy 516.469215, cx 318.643040, cy 255.313989, k1 k2 p1 p2 k3 0.262383 -0.953104 -0.005358 0.002628 1.163314
	Freiburg2, // fx 520.908620, fy 521.007327, cx 325.141442, cy 249.701764, k1 k2 p1 p2 k3 0.231222 -0.784899 -0.003257 -0.000105 0.917205
	Freiburg3, // fx 535.4, fy 539.2, cx 320.1, cy 247.6, no distortion (its images are already undistorted)
};

PinholeParams tum_camera_intrinsics(TumCamera p_camera);
// The camera a sequence was recorded with, from "freiburg1"/"freiburg2"/"freiburg3" (or "fr1"
// ...) in its folder name, e.g. rgbd_dataset_freiburg1_xyz; false when the name says none.
bool tum_camera_from_folder_name(const std::string &p_folder, TumCamera *r_camera);

struct TumDatasetOptions {
	PinholeParams rgb = tum_camera_intrinsics(TumCamera::RosDefault); // size must match the images
	double depth_factor = 5000.0; // depth units per metre (TUM: 5000)
	double max_difference_s = 0.02; // RGB and depth pair when closer than this (associate.py's default)
};

// Opens the sequence in p_folder into r_reader, which then plays it like a recording (rig: the
// given intrinsics, depth_scale_m = 1 / depth_factor, no fisheye). Fails, naming the file, when
// rgb.txt or depth.txt is missing or unreadable or the options are unusable. Lines that do not
// parse, timestamps that go backwards, and missing, truncated or wrong-size images are issues;
// frames without a partner are summed up in one issue per index (associate.py drops them too);
// a missing groundtruth.txt is an issue (TUM's validation sequences have none).
RecordingStatus open_tum_dataset(const std::string &p_folder, RecordingReader *r_reader, const TumDatasetOptions &p_options = TumDatasetOptions());

} // namespace roomprobe
