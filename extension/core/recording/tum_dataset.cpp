#include "tum_dataset.h"

#include "recording_io.h"

#include <io/input_path.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace roomprobe {

namespace fs = std::filesystem;
using recording_io::format_number;
using recording_io::join;

PinholeParams tum_camera_intrinsics(TumCamera p_camera) {
	PinholeParams params;
	params.width = 640;
	params.height = 480;
	switch (p_camera) {
		case TumCamera::RosDefault:
			params.fx = 525.0;
			params.fy = 525.0;
			params.cx = 319.5;
			params.cy = 239.5;
			break;
		case TumCamera::Freiburg1:
			params.fx = 517.306408;
			params.fy = 516.469215;
			params.cx = 318.643040;
			params.cy = 255.313989;
			params.k1 = 0.262383;
			params.k2 = -0.953104;
			params.p1 = -0.005358;
			params.p2 = 0.002628;
			params.k3 = 1.163314;
			break;
		case TumCamera::Freiburg2:
			params.fx = 520.908620;
			params.fy = 521.007327;
			params.cx = 325.141442;
			params.cy = 249.701764;
			params.k1 = 0.231222;
			params.k2 = -0.784899;
			params.p1 = -0.003257;
			params.p2 = -0.000105;
			params.k3 = 0.917205;
			break;
		case TumCamera::Freiburg3:
			params.fx = 535.4;
			params.fy = 539.2;
			params.cx = 320.1;
			params.cy = 247.6;
			break;
	}
	return params;
}

bool tum_camera_from_folder_name(const std::string &p_folder, TumCamera *r_camera) {
	fs::path path(p_folder);
	if (path.filename().empty()) {
		path = path.parent_path(); // "seq/" names "seq"
	}
	std::string name = path.filename().string();
	std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	const struct {
		const char *long_name;
		const char *short_name;
		TumCamera camera;
	} cameras[3] = { { "freiburg1", "fr1", TumCamera::Freiburg1 }, { "freiburg2", "fr2", TumCamera::Freiburg2 }, { "freiburg3", "fr3", TumCamera::Freiburg3 } };
	for (const auto &camera : cameras) {
		if (name.find(camera.long_name) != std::string::npos) {
			*r_camera = camera.camera;
			return true;
		}
	}
	// "fr1" only as a word of its own ("fr1_xyz", "tum_fr1"), not inside another word.
	for (const auto &camera : cameras) {
		const size_t at = name.find(camera.short_name);
		if (at == std::string::npos) {
			continue;
		}
		const size_t end = at + 3;
		const bool starts = at == 0 || !std::isalnum(static_cast<unsigned char>(name[at - 1]));
		const bool ends = end == name.size() || !std::isalnum(static_cast<unsigned char>(name[end]));
		if (starts && ends) {
			*r_camera = camera.camera;
			return true;
		}
	}
	return false;
}

RecordingStatus open_tum_dataset(const std::string &p_folder, RecordingReader *r_reader, const TumDatasetOptions &p_options) {
	RecordingStatus status;
	r_reader->close();
	std::error_code ec;
	status.error = input_folder_problem(p_folder, "no such TUM RGB-D sequence folder");
	if (!status.error.empty()) {
		return status;
	}
	const PinholeParams &rgb = p_options.rgb;
	if (rgb.width <= 0 || rgb.height <= 0 || !(rgb.fx > 0.0) || !(rgb.fy > 0.0) || !std::isfinite(rgb.cx) || !std::isfinite(rgb.cy)) {
		status.error = p_folder + ": TumDatasetOptions::rgb: needs a positive size and focal lengths";
		return status;
	}
	if (!(p_options.depth_factor > 0.0) || !std::isfinite(p_options.depth_factor)) {
		status.error = p_folder + ": TumDatasetOptions::depth_factor: must be positive (got " + format_number(p_options.depth_factor) + ")";
		return status;
	}
	if (!(p_options.max_difference_s > 0.0) || !std::isfinite(p_options.max_difference_s)) {
		status.error = p_folder + ": TumDatasetOptions::max_difference_s: must be positive (got " + format_number(p_options.max_difference_s) + ")";
		return status;
	}

	RecordingContents contents;
	contents.folder = p_folder;
	contents.rig.rgb = rgb;
	contents.rig.depth_scale_m = 1.0 / p_options.depth_factor;
	contents.rig.fisheye = OmniParams(); // none: width 0
	contents.has_room = false;

	const std::string rgb_index = join(p_folder, "rgb.txt");
	const std::string depth_index = join(p_folder, "depth.txt");
	std::vector<FrameRef> rgb_frames;
	std::vector<FrameRef> depth_frames;
	std::string error = recording_io::read_frame_index(rgb_index, &rgb_frames, &contents.issues);
	if (error.empty()) {
		error = recording_io::read_frame_index(depth_index, &depth_frames, &contents.issues);
	}
	if (!error.empty()) {
		status.error = error;
		return status;
	}
	recording_io::pair_and_check_rgbd(rgb_frames, rgb_index, depth_frames, depth_index, p_options.max_difference_s, true, &contents);

	const std::string groundtruth = join(p_folder, "groundtruth.txt");
	if (fs::exists(groundtruth, ec)) {
		TrajectoryLoadResult trajectory = load_tum_trajectory(groundtruth);
		if (trajectory.ok) {
			contents.has_ground_truth[int(RecordingStream::Rgbd)] = true;
			contents.ground_truth[int(RecordingStream::Rgbd)] = std::move(trajectory.trajectory);
		} else {
			contents.issues.push_back(recording_io::issue_from_error(groundtruth, trajectory.error, "; no ground-truth trajectory"));
		}
	} else {
		contents.issues.push_back({ groundtruth, 0, "missing; no ground-truth trajectory" });
	}

	r_reader->open_contents(std::move(contents));
	status.ok = true;
	return status;
}

} // namespace roomprobe
