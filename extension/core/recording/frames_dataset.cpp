#include "frames_dataset.h"

#include "recording_io.h"

#include <io/input_path.h>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace roomprobe {

namespace fs = std::filesystem;
using recording_io::format_number;
using recording_io::join;

namespace {

constexpr const char *INTRINSICS_FILE = "camera-intrinsics.txt";
// A pose's rotation may be this far from orthonormal (entries of R^T R - I) and its last row
// this far from 0 0 0 1; the files keep many digits, so anything further is not a rigid pose.
constexpr double POSE_TOLERANCE = 1e-3;

// The files of one frame number; empty where there is none.
struct FrameFiles {
	std::string color, depth, pose; // names relative to the folder
	std::string other_color; // a second colour image of the same number (the PNG is used)
};

// "frame-000012.depth.png" -> 12 and "depth.png"; false for any other name.
bool parse_frame_name(const std::string &p_name, long *r_number, int *r_digits, std::string *r_kind) {
	const std::string prefix = "frame-";
	if (p_name.rfind(prefix, 0) != 0) {
		return false;
	}
	size_t at = prefix.size();
	while (at < p_name.size() && std::isdigit(static_cast<unsigned char>(p_name[at]))) {
		at++;
	}
	const size_t digits = at - prefix.size();
	if (digits == 0 || digits > 9 || at >= p_name.size() || p_name[at] != '.') {
		return false;
	}
	*r_kind = p_name.substr(at + 1);
	*r_number = std::stol(p_name.substr(prefix.size(), digits));
	*r_digits = int(digits);
	return true;
}

std::string frame_name(long p_number, int p_digits, const char *p_kind) {
	std::string number = std::to_string(p_number);
	if (int(number.size()) < p_digits) {
		number.insert(0, size_t(p_digits) - number.size(), '0');
	}
	return "frame-" + number + "." + p_kind;
}

// A whitespace-separated matrix of p_rows x p_cols numbers, one row a line (blank lines skipped),
// row-major into r_values. The error names the file and the line.
std::string read_text_matrix(const std::string &p_path, int p_rows, int p_cols, std::vector<double> *r_values) {
	std::error_code ec;
	if (!fs::is_regular_file(p_path, ec)) {
		return recording_io::not_a_file_error(p_path);
	}
	std::ifstream file(p_path, std::ios::binary);
	if (!file) {
		return p_path + ": cannot be opened for reading";
	}
	r_values->clear();
	std::string line;
	int number = 0;
	int rows = 0;
	while (std::getline(file, line)) {
		number++;
		std::istringstream fields(line);
		std::string field;
		std::vector<double> row;
		while (fields >> field) {
			double value = 0.0;
			if (!recording_io::parse_number(field, &value)) {
				return p_path + ":" + std::to_string(number) + ": '" + field + "' is not a finite number";
			}
			row.push_back(value);
		}
		if (row.empty()) {
			continue;
		}
		if (int(row.size()) != p_cols) {
			return p_path + ":" + std::to_string(number) + ": expected " + std::to_string(p_cols) + " numbers, got " + std::to_string(row.size());
		}
		if (++rows > p_rows) {
			return p_path + ":" + std::to_string(number) + ": more than the " + std::to_string(p_rows) + " rows of a " + std::to_string(p_rows) + "x" +
					std::to_string(p_cols) + " matrix";
		}
		r_values->insert(r_values->end(), row.begin(), row.end());
	}
	if (file.bad()) {
		return p_path + ": read error after line " + std::to_string(number);
	}
	if (rows < p_rows) {
		return p_path + ": " + std::to_string(rows) + " rows, expected the " + std::to_string(p_rows) + " of a " + std::to_string(p_rows) + "x" +
				std::to_string(p_cols) + " matrix";
	}
	return std::string();
}

// camera-intrinsics.txt: fx 0 cx / 0 fy cy / 0 0 1.
std::string read_intrinsics(const std::string &p_path, PinholeParams *r_params) {
	std::vector<double> k;
	const std::string error = read_text_matrix(p_path, 3, 3, &k);
	if (!error.empty()) {
		return error;
	}
	if (!(k[0] > 0.0) || !(k[4] > 0.0)) {
		return p_path + ": fx and fy (K[0][0], K[1][1]) must be positive (got " + format_number(k[0]) + ", " + format_number(k[4]) + ")";
	}
	if (k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0) {
		return p_path + ": not a pinhole K without skew (expected 'fx 0 cx', '0 fy cy', '0 0 1')";
	}
	r_params->fx = k[0];
	r_params->cx = k[2];
	r_params->fy = k[4];
	r_params->cy = k[5];
	return std::string();
}

// frame-NNNNNN.pose.txt: a 4x4 world_from_camera.
std::string read_pose(const std::string &p_path, Pose *r_pose) {
	std::vector<double> m;
	const std::string error = read_text_matrix(p_path, 4, 4, &m);
	if (!error.empty()) {
		return error;
	}
	const double last_row[4] = { m[12], m[13], m[14], m[15] };
	const double expected[4] = { 0.0, 0.0, 0.0, 1.0 };
	for (int i = 0; i < 4; i++) {
		if (!(std::abs(last_row[i] - expected[i]) <= POSE_TOLERANCE)) {
			return p_path + ": the last row must be 0 0 0 1 (a rigid transform); got " + format_number(m[12]) + " " + format_number(m[13]) + " " +
					format_number(m[14]) + " " + format_number(m[15]);
		}
	}
	glm::dmat3 rotation;
	for (int row = 0; row < 3; row++) {
		for (int col = 0; col < 3; col++) {
			rotation[col][row] = m[size_t(row * 4 + col)]; // glm is column-major
		}
	}
	const glm::dmat3 gram = glm::transpose(rotation) * rotation;
	double worst = 0.0;
	for (int row = 0; row < 3; row++) {
		for (int col = 0; col < 3; col++) {
			worst = std::max(worst, std::abs(gram[col][row] - (row == col ? 1.0 : 0.0)));
		}
	}
	if (!(worst <= POSE_TOLERANCE) || !(glm::determinant(rotation) > 0.0)) {
		return p_path + ": the upper-left 3x3 is not a rotation (R^T R differs from the identity by " + format_number(worst) + ", det " +
				format_number(glm::determinant(rotation)) + ")";
	}
	glm::dmat4 matrix(rotation);
	matrix[3] = glm::dvec4(m[3], m[7], m[11], 1.0);
	*r_pose = pose_from_matrix(matrix);
	return std::string();
}

// The frames by number (r_digits: their numbers' width, left as it is when there are none); the
// error when the folder cannot be listed or holds no depth image.
std::string list_frames(const std::string &p_folder, std::map<long, FrameFiles> *r_frames, int *r_digits) {
	std::map<long, FrameFiles> &frames = *r_frames;
	std::error_code ec;
	for (fs::directory_iterator it(p_folder, ec), end; !ec && it != end; it.increment(ec)) {
		const std::string name = it->path().filename().string();
		long number = 0;
		int width = 0;
		std::string kind;
		if (!parse_frame_name(name, &number, &width, &kind)) {
			continue;
		}
		FrameFiles &files = frames[number];
		*r_digits = width;
		if (kind == "depth.png") {
			files.depth = name;
		} else if (kind == "pose.txt") {
			files.pose = name;
		} else if (kind == "color.png" || kind == "color.jpg" || kind == "color.jpeg") {
			// Both a PNG and a JPEG: the PNG (lossless) is used.
			const bool png = kind == "color.png";
			if (files.color.empty()) {
				files.color = name;
			} else if (png) {
				files.other_color = files.color;
				files.color = name;
			} else {
				files.other_color = name;
			}
		}
	}
	if (ec) {
		return p_folder + ": cannot list the folder (" + ec.message() + ")";
	}
	size_t depth_files = 0;
	for (const auto &[number, files] : frames) {
		depth_files += files.depth.empty() ? 0 : 1;
	}
	if (depth_files == 0) {
		return p_folder + ": no frame-NNNNNN.depth.png (not a 7-Scenes-style folder of frames)";
	}
	return std::string();
}

// Intrinsics, then the size from the first depth image whose header reads.
std::string read_colour_camera(const std::string &p_folder, const std::map<long, FrameFiles> &p_frames, const FramesDatasetOptions &p_options,
		PinholeParams *r_rgb) {
	PinholeParams &rgb = *r_rgb;
	if (p_options.override_intrinsics) {
		rgb = p_options.intrinsics;
		if (!(rgb.fx > 0.0) || !(rgb.fy > 0.0) || !std::isfinite(rgb.cx) || !std::isfinite(rgb.cy) || rgb.width < 0 || rgb.height < 0) {
			return p_folder + ": FramesDatasetOptions::intrinsics: needs positive focal lengths, a finite principal point and a size >= 0";
		}
	} else {
		const std::string error = read_intrinsics(join(p_folder, INTRINSICS_FILE), &rgb);
		if (!error.empty()) {
			return error;
		}
	}
	if (rgb.width == 0 || rgb.height == 0) {
		std::string first_error;
		for (const auto &[number, files] : p_frames) {
			if (files.depth.empty()) {
				continue;
			}
			recording_io::PngInfo info;
			const std::string error = recording_io::read_png_info(join(p_folder, files.depth), &info);
			if (error.empty()) {
				rgb.width = info.width;
				rgb.height = info.height;
				break;
			}
			first_error = first_error.empty() ? error : first_error;
		}
		if (rgb.width == 0) {
			return p_folder + ": no depth image gives the image size (" + first_error + ")";
		}
	}
	return std::string();
}

// The kind a missing colour image is named by: that of the first frame with one.
std::string colour_kind(const std::map<long, FrameFiles> &p_frames) {
	for (const auto &[number, files] : p_frames) {
		if (!files.color.empty()) {
			return files.color.substr(files.color.find('.') + 1);
		}
	}
	return std::string("color.jpg");
}

void add_gap_issue(const std::string &p_folder, long p_previous, long p_number, int p_digits, RecordingContents *r_contents) {
	const std::string first = frame_name(p_previous + 1, p_digits, "*"), last = frame_name(p_number - 1, p_digits, "*");
	r_contents->issues.push_back({ p_folder, 0,
			"gap in the numbering: " + (p_number == p_previous + 2 ? first : first + " to " + last) + " missing (" + std::to_string(p_number - p_previous - 1) +
					" frames between " + frame_name(p_previous, p_digits, "*") + " and " + frame_name(p_number, p_digits, "*") +
					"); the frames after keep their times" });
}

// The RGB-D frames and ground-truth poses into r_contents; gaps in the numbering, and frames short
// of an image, become issues.
void add_frames(const std::string &p_folder, const std::map<long, FrameFiles> &p_frames, int p_digits, const FramesDatasetOptions &p_options,
		RecordingContents *r_contents) {
	RecordingContents &contents = *r_contents;
	const std::string color_kind = colour_kind(p_frames);
	std::vector<FrameRef> rgb_frames, depth_frames;
	std::vector<TimedPose> poses;
	size_t without_pose = 0;
	std::string first_without_pose;
	long previous = -1;
	for (const auto &[number, files] : p_frames) {
		if (previous >= 0 && number > previous + 1) {
			add_gap_issue(p_folder, previous, number, p_digits, &contents);
		}
		previous = number;
		const double t_s = double(number) / p_options.frame_rate_hz;
		if (!files.other_color.empty()) {
			contents.issues.push_back({ join(p_folder, files.other_color), 0, "a second colour image of the frame; " + files.color + " is used" });
		}
		if (files.color.empty() || files.depth.empty()) {
			const std::string missing = files.color.empty() ? frame_name(number, p_digits, color_kind.c_str()) : frame_name(number, p_digits, "depth.png");
			contents.issues.push_back({ join(p_folder, missing), 0, "missing; RGB-D frame skipped" });
		} else {
			rgb_frames.push_back(FrameRef{ t_s, files.color, 0 });
			depth_frames.push_back(FrameRef{ t_s, files.depth, 0 });
		}
		if (files.pose.empty()) {
			without_pose++;
			first_without_pose = first_without_pose.empty() ? frame_name(number, p_digits, "pose.txt") : first_without_pose;
			continue;
		}
		Pose pose;
		const std::string error = read_pose(join(p_folder, files.pose), &pose);
		if (error.empty()) {
			poses.push_back(TimedPose{ t_s, pose });
		} else {
			contents.issues.push_back(recording_io::issue_from_error(join(p_folder, files.pose), error, "; no ground-truth pose at this frame"));
		}
	}
	if (without_pose > 0) {
		contents.issues.push_back({ join(p_folder, first_without_pose), 0,
				"missing; " + std::to_string(without_pose) + " of " + std::to_string(p_frames.size()) + " frames have no pose file (this is the first)" +
						(poses.empty() ? ": no ground-truth trajectory" : "") });
	}
	// Paired by construction (same timestamps): this checks each pair's images from their headers.
	recording_io::pair_and_check_rgbd(rgb_frames, p_folder, depth_frames, p_folder, 0.25 / p_options.frame_rate_hz, false, &contents);
	if (!poses.empty()) {
		std::string error;
		if (contents.ground_truth[int(RecordingStream::Rgbd)].set_samples(std::move(poses), &error)) {
			contents.has_ground_truth[int(RecordingStream::Rgbd)] = true;
		} else {
			contents.issues.push_back({ p_folder, 0, "poses: " + error + "; no ground-truth trajectory" }); // unreachable: each was checked
		}
	}
}

} // namespace

RecordingStatus open_frames_dataset(const std::string &p_folder, RecordingReader *r_reader, const FramesDatasetOptions &p_options) {
	RecordingStatus status;
	r_reader->close();
	status.error = input_folder_problem(p_folder, "no such frames folder");
	if (!status.error.empty()) {
		return status;
	}
	if (!(p_options.depth_scale_m > 0.0) || !std::isfinite(p_options.depth_scale_m)) {
		status.error = p_folder + ": FramesDatasetOptions::depth_scale_m: must be positive (got " + format_number(p_options.depth_scale_m) + ")";
		return status;
	}
	if (!(p_options.frame_rate_hz > 0.0) || !std::isfinite(p_options.frame_rate_hz)) {
		status.error = p_folder + ": FramesDatasetOptions::frame_rate_hz: must be positive (got " + format_number(p_options.frame_rate_hz) + ")";
		return status;
	}
	std::map<long, FrameFiles> frames;
	int digits = 6;
	status.error = list_frames(p_folder, &frames, &digits);
	if (!status.error.empty()) {
		return status;
	}
	RecordingContents contents;
	contents.folder = p_folder;
	contents.rig.depth_scale_m = p_options.depth_scale_m;
	contents.rig.fisheye = OmniParams(); // none
	contents.has_room = false;
	status.error = read_colour_camera(p_folder, frames, p_options, &contents.rig.rgb);
	if (!status.error.empty()) {
		return status;
	}
	add_frames(p_folder, frames, digits, p_options, &contents);
	r_reader->open_contents(std::move(contents));
	status.ok = true;
	return status;
}

} // namespace roomprobe
