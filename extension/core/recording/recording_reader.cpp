#include "recording_reader.h"

#include <types/cubemap_layout.h>
#include "recording_io.h"
#include "room_file.h"

#include <io/input_path.h>


#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>

namespace roomprobe {

namespace fs = std::filesystem;
using recording_io::format_number;
using recording_io::join;

namespace {

std::string lower_extension(const std::string &p_path) {
	std::string extension = fs::path(p_path).extension().string();
	std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	return extension;
}

std::string size_text(int p_width, int p_height) {
	return std::to_string(p_width) + "x" + std::to_string(p_height);
}

std::string size_problem(const std::string &p_path, int p_width, int p_height, const char *p_camera, int p_rig_width, int p_rig_height) {
	if (p_width == p_rig_width && p_height == p_rig_height) {
		return std::string();
	}
	return p_path + ": " + size_text(p_width, p_height) + " pixels, but the rig's " + p_camera + " is " + size_text(p_rig_width, p_rig_height);
}

const char *png_color_name(int p_color_type) {
	switch (p_color_type) {
		case 0:
			return "gray";
		case 2:
			return "RGB";
		case 3:
			return "palette";
		case 4:
			return "gray+alpha";
		case 6:
			return "RGBA";
		default:
			return "unknown colour type";
	}
}

std::string describe_png(const recording_io::PngInfo &p_info) {
	return std::to_string(p_info.bit_depth) + "-bit " + png_color_name(p_info.color_type);
}

// The checks open() can make from an image's header: "" or the problem, naming the file.
std::string check_rgb_image(const std::string &p_path, const Rig &p_rig) {
	if (recording_io::is_jpeg_path(p_path)) {
		recording_io::JpegInfo jpeg;
		const std::string error = recording_io::read_jpeg_info(p_path, &jpeg);
		if (!error.empty()) {
			return error;
		}
		if (jpeg.components != 3) {
			return p_path + ": an RGB image must be a colour JPEG (3 components); this has " + std::to_string(jpeg.components);
		}
		return size_problem(p_path, jpeg.width, jpeg.height, "RGB-D camera", p_rig.rgb.width, p_rig.rgb.height);
	}
	recording_io::FrameFileInfo info;
	const std::string error = recording_io::read_frame_file_info(p_path, &info);
	if (!error.empty()) {
		return error;
	}
	if (info.kind == recording_io::FrameFileKind::RawFrame && info.raw.cv_type() != CV_8UC3) {
		return p_path + ": an RGB image must be 8-bit with 3 channels (R, G, B); this raw frame is " + recording_io::describe_type(info.raw.cv_type());
	}
	if (info.kind == recording_io::FrameFileKind::Png &&
			(info.png.bit_depth != 8 || (info.png.color_type != 2 && info.png.color_type != 3 && info.png.color_type != 6))) {
		return p_path + ": an RGB image must be an 8-bit RGB PNG; this is " + describe_png(info.png);
	}
	return size_problem(p_path, info.width, info.height, "RGB-D camera", p_rig.rgb.width, p_rig.rgb.height);
}

std::string check_depth_image(const std::string &p_path, const Rig &p_rig) {
	recording_io::FrameFileInfo info;
	const std::string error = recording_io::read_frame_file_info(p_path, &info);
	if (!error.empty()) {
		return error;
	}
	if (info.kind == recording_io::FrameFileKind::RawFrame && info.raw.cv_type() != CV_16UC1) {
		return p_path + ": a depth image must be 16-bit with 1 channel; this raw frame is " + recording_io::describe_type(info.raw.cv_type());
	}
	if (info.kind == recording_io::FrameFileKind::Png && (info.png.bit_depth != 16 || info.png.color_type != 0)) {
		return p_path + ": a depth image must be a 16-bit gray PNG; this is " + describe_png(info.png);
	}
	return size_problem(p_path, info.width, info.height, "RGB-D camera", p_rig.rgb.width, p_rig.rgb.height);
}

// The raw frames a fisheye stream takes: 8-bit gray or R, G, B (HDR frames are EXR files).
bool fisheye_raw_type(int p_cv_type) {
	return p_cv_type == CV_8UC1 || p_cv_type == CV_8UC3;
}

std::string check_fisheye_file(const std::string &p_path, const Rig &p_rig) {
	const std::string extension = lower_extension(p_path);
	int width = 0;
	int height = 0;
	if (extension == ".exr") {
		const std::string error = recording_io::read_exr_size(p_path, &width, &height);
		if (!error.empty()) {
			return error;
		}
	} else {
		recording_io::FrameFileInfo info;
		const std::string error = recording_io::read_frame_file_info(p_path, &info);
		if (!error.empty()) {
			return error;
		}
		if (info.kind == recording_io::FrameFileKind::RawFrame && !fisheye_raw_type(info.raw.cv_type())) {
			return p_path + ": a fisheye raw frame must be 8-bit gray or R, G, B (HDR frames are EXR files); this is " +
					recording_io::describe_type(info.raw.cv_type());
		}
		if (info.kind == recording_io::FrameFileKind::Png && info.png.bit_depth != 8) {
			return p_path + ": a fisheye PNG must be 8-bit (gray or RGB); this is " + describe_png(info.png);
		}
		width = info.width;
		height = info.height;
	}
	if (p_rig.fisheye.width <= 0) {
		return std::string(); // a rig without a fisheye (datasets): nothing to compare with
	}
	return size_problem(p_path, width, height, "fisheye", p_rig.fisheye.width, p_rig.fisheye.height);
}

// Reads gaps.txt (a live recording's frames its writer could not keep): one issue a gap, so
// whoever plays it back knows where frames are missing.
void read_gap_list(const std::string &p_path, RecordingContents *r_contents) {
	std::vector<recording_io::IndexLine> lines;
	const std::string error = recording_io::read_index_lines(p_path, &lines);
	if (!error.empty()) {
		r_contents->issues.push_back({ p_path, 0, error });
		return;
	}
	for (const recording_io::IndexLine &line : lines) {
		std::istringstream fields(line.text);
		std::string stream;
		double first_s = 0.0, last_s = 0.0;
		unsigned long long frames = 0;
		if (!(fields >> stream >> first_s >> last_s >> frames) || (stream != "rgbd" && stream != "fisheye")) {
			r_contents->issues.push_back({ p_path, line.line, "expected 'rgbd|fisheye first_timestamp_s last_timestamp_s frames', got '" + line.text + "'" });
			continue;
		}
		r_contents->issues.push_back({ p_path, line.line, std::to_string(frames) + " " + stream + " frame" + (frames == 1 ? "" : "s") +
				" from " + recording_io::format_number(first_s) + " to " + recording_io::format_number(last_s) +
				" s were not recorded (the recorder's queue was full)" });
	}
}

// Reads capture.txt (what a live recording's devices said about each frame). A line that does
// not parse, or names no frame of its stream, is an issue; the frames play either way.
void read_capture_list(const std::string &p_path, RecordingContents *r_contents) {
	std::vector<recording_io::IndexLine> lines;
	const std::string error = recording_io::read_index_lines(p_path, &lines);
	if (!error.empty()) {
		r_contents->issues.push_back({ p_path, 0, error + "; frames have no capture information" });
		return;
	}
	std::set<double> frame_times[2];
	for (const RgbdFrameRef &ref : r_contents->rgbd) {
		frame_times[0].insert(ref.rgb.timestamp_s);
	}
	for (const FrameRef &ref : r_contents->fisheye) {
		frame_times[1].insert(ref.timestamp_s);
	}
	// A number or "nan" (not reported).
	const auto value = [](const std::string &p_text, double *r_value) {
		if (p_text == "nan") {
			*r_value = std::numeric_limits<double>::quiet_NaN();
			return true;
		}
		return recording_io::parse_number(p_text, r_value);
	};
	for (const recording_io::IndexLine &line : lines) {
		std::istringstream fields(line.text);
		std::string stream, stamp, device_time, frame_id, exposure, gain, extra;
		CaptureInfo info;
		double timestamp_s = 0.0;
		char *end = nullptr;
		const bool parsed = bool(fields >> stream >> stamp >> device_time >> frame_id >> exposure >> gain) && !(fields >> extra) &&
				(stream == "rgbd" || stream == "fisheye") && recording_io::parse_number(stamp, &timestamp_s) && value(device_time, &info.device_time_s) &&
				value(exposure, &info.exposure_us) && value(gain, &info.gain) &&
				(info.device_frame_id = std::strtoll(frame_id.c_str(), &end, 10), end != frame_id.c_str() && *end == '\0') && info.device_frame_id >= -1;
		if (!parsed) {
			r_contents->issues.push_back({ p_path, line.line, "expected 'rgbd|fisheye timestamp_s device_time_s device_frame_id exposure_us gain' "
															  "(numbers, nan where unknown, frame id -1 where unknown), got '" + line.text + "'; line skipped" });
			continue;
		}
		// What a device can have said (issue #38: zero or negative exposures, absurd gains were
		// used): an exposure of at most 10 s (RigCapture.exposure_us's bound), a gain in [0, 1000].
		if (!std::isnan(info.exposure_us) && !(info.exposure_us > 0.0 && info.exposure_us <= 1e7)) {
			r_contents->issues.push_back({ p_path, line.line, "exposure_us " + exposure + " is not in (0, 10000000] (nan where unknown); line skipped" });
			continue;
		}
		if (!std::isnan(info.gain) && !(info.gain >= 0.0 && info.gain <= 1000.0)) {
			r_contents->issues.push_back({ p_path, line.line, "gain " + gain + " is not in [0, 1000] (nan where unknown); line skipped" });
			continue;
		}
		const int s = stream == "rgbd" ? 0 : 1;
		if (!frame_times[s].count(timestamp_s)) {
			r_contents->issues.push_back({ p_path, line.line, "no " + stream + " frame has timestamp " + stamp + "; line skipped" });
			continue;
		}
		r_contents->capture[s][timestamp_s] = info;
	}
}

// The capture information of a stream's frame at p_timestamp_s; unknown when there is none.
CaptureInfo capture_of(const RecordingContents &p_contents, RecordingStream p_stream, double p_timestamp_s) {
	const std::map<double, CaptureInfo> &list = p_contents.capture[p_stream == RecordingStream::Rgbd ? 0 : 1];
	const auto found = list.find(p_timestamp_s);
	return found == list.end() ? CaptureInfo() : found->second;
}

// Issue #38: timestamps written in milliseconds played 1000 times slower without a word. A camera's
// frames come a few milliseconds to a few seconds apart; a median spacing beyond 5 s (or below
// 0.1 ms) means the index is in another unit. The frames still play, as stamped.
void note_unlikely_frame_spacing(const std::string &p_index, const std::vector<FrameRef> &p_frames, std::vector<RecordingIssue> *r_issues) {
	if (p_frames.size() < 3) {
		return;
	}
	std::vector<double> spacing;
	for (size_t i = 1; i < p_frames.size(); i++) {
		spacing.push_back(p_frames[i].timestamp_s - p_frames[i - 1].timestamp_s);
	}
	std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
	const double median_s = spacing[spacing.size() / 2];
	if (median_s > 5.0 || median_s < 1e-4) {
		r_issues->push_back({ p_index, 0,
				"frames are " + format_number(median_s) + " s apart (median): timestamps must be in seconds (milliseconds or nanoseconds?); played as stamped" });
	}
}

// Reads groundtruth/cubemaps.txt: 'timestamp_s probe_index relative/path.exr' a line.
void read_cubemap_index(const std::string &p_folder, const std::string &p_path, const RoomInfo &p_room, RecordingContents *r_contents) {
	std::vector<recording_io::IndexLine> lines;
	const std::string error = recording_io::read_index_lines(p_path, &lines);
	if (!error.empty()) {
		r_contents->issues.push_back({ p_path, 0, error + "; no ground-truth cubemaps" });
		return;
	}
	for (const recording_io::IndexLine &line : lines) {
		const std::string &text = line.text;
		const size_t first = text.find_first_of(" \t");
		const size_t second_start = first == std::string::npos ? std::string::npos : text.find_first_not_of(" \t", first);
		const size_t second = second_start == std::string::npos ? std::string::npos : text.find_first_of(" \t", second_start);
		if (second == std::string::npos) {
			r_contents->issues.push_back({ p_path, line.line, "expected 'timestamp_s probe_index relative/path.exr', got '" + text + "'; line skipped" });
			continue;
		}
		CubemapRef ref;
		ref.line = line.line;
		const std::string stamp = text.substr(0, first);
		const std::string probe = text.substr(second_start, second - second_start);
		std::string path = text.substr(second);
		path.erase(0, path.find_first_not_of(" \t"));
		if (!recording_io::parse_number(stamp, &ref.timestamp_s)) {
			r_contents->issues.push_back({ p_path, line.line, "'" + stamp + "' is not a finite timestamp in seconds; line skipped" });
			continue;
		}
		if (!recording_io::parse_int(probe, &ref.probe_index) || ref.probe_index < 0 || size_t(ref.probe_index) >= p_room.probes.size()) {
			r_contents->issues.push_back({ p_path, line.line,
					"probe index '" + probe + "' is not one of room.yaml's " + std::to_string(p_room.probes.size()) + " probes; cubemap skipped" });
			continue;
		}
		const std::string outside = recording_io::path_leaves_recording(path);
		if (!outside.empty()) {
			r_contents->issues.push_back({ p_path, line.line, outside + "; cubemap skipped" });
			continue;
		}
		if (!r_contents->cubemaps.empty() && ref.timestamp_s < r_contents->cubemaps.back().timestamp_s) {
			r_contents->issues.push_back({ p_path, line.line,
					"timestamp " + format_number(ref.timestamp_s) + " goes backwards (before " + format_number(r_contents->cubemaps.back().timestamp_s) +
							" at line " + std::to_string(r_contents->cubemaps.back().line) + "); cubemap " + path + " skipped" });
			continue;
		}
		const std::string full_path = join(p_folder, path);
		int width = 0;
		int height = 0;
		std::string problem = recording_io::read_exr_size(full_path, &width, &height);
		if (problem.empty() && height != 6 * width) {
			problem = full_path + ": " + size_text(width, height) + " pixels is not a cubemap strip (N wide, 6N tall)";
		}
		if (!problem.empty()) {
			r_contents->issues.push_back({ p_path, line.line, problem + "; cubemap skipped" });
			continue;
		}
		ref.path = path;
		r_contents->cubemaps.push_back(ref);
	}
}

// Decodes an 8-bit colour PNG, a colour JPEG or an 8-bit R, G, B raw frame into CV_8UC3 R, G, B.
std::string decode_rgb8(const std::string &p_path, cv::Mat *r_rgb) {
	cv::Mat image;
	recording_io::FrameFileKind kind = recording_io::FrameFileKind::Png;
	const std::string error =
			recording_io::is_jpeg_path(p_path) ? recording_io::decode_jpeg(p_path, &image) : recording_io::decode_frame_file(p_path, &image, &kind);
	if (!error.empty()) {
		return error;
	}
	if (kind == recording_io::FrameFileKind::RawFrame) {
		if (image.type() != CV_8UC3) {
			return p_path + ": must be an 8-bit RGB image; this raw frame is " + recording_io::describe_type(image.type());
		}
		*r_rgb = image; // stored as R, G, B
		return std::string();
	}
	if (image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 4)) {
		return p_path + ": must be an 8-bit RGB image; this decodes as " + recording_io::describe_type(image.type());
	}
	cv::cvtColor(image, *r_rgb, image.channels() == 4 ? cv::COLOR_BGRA2RGB : cv::COLOR_BGR2RGB);
	return std::string();
}

} // namespace

void recording_io::pair_and_check_rgbd(const std::vector<FrameRef> &p_rgb, const std::string &p_rgb_index, const std::vector<FrameRef> &p_depth,
		const std::string &p_depth_index, double p_max_difference_s, bool p_summarise_unpaired, RecordingContents *r_contents) {
	std::vector<double> rgb_times;
	std::vector<double> depth_times;
	for (const FrameRef &frame : p_rgb) {
		rgb_times.push_back(frame.timestamp_s);
	}
	for (const FrameRef &frame : p_depth) {
		depth_times.push_back(frame.timestamp_s);
	}
	std::vector<std::pair<size_t, size_t>> pairs;
	associate(rgb_times, depth_times, p_max_difference_s, &pairs);

	// Unpaired frames.
	std::vector<bool> rgb_paired(p_rgb.size(), false);
	std::vector<bool> depth_paired(p_depth.size(), false);
	for (const auto &[rgb, depth] : pairs) {
		rgb_paired[rgb] = true;
		depth_paired[depth] = true;
	}
	const std::string window = format_number(p_max_difference_s) + " s";
	struct Side {
		const std::vector<FrameRef> &frames;
		const std::vector<bool> &paired;
		const std::string &index;
		const char *other;
	};
	const Side sides[2] = { { p_rgb, rgb_paired, p_rgb_index, "depth" }, { p_depth, depth_paired, p_depth_index, "RGB" } };
	for (const Side &side : sides) {
		size_t unpaired = 0;
		for (size_t i = 0; i < side.frames.size(); i++) {
			if (side.paired[i]) {
				continue;
			}
			unpaired++;
			if (!p_summarise_unpaired) {
				r_contents->issues.push_back({ side.index, side.frames[i].line,
						"no " + std::string(side.other) + " frame within " + window + " of " + format_number(side.frames[i].timestamp_s) + "; frame " +
								side.frames[i].path + " skipped" });
			}
		}
		if (p_summarise_unpaired && unpaired > 0) {
			r_contents->issues.push_back({ side.index, 0,
					std::to_string(unpaired) + " of " + std::to_string(side.frames.size()) + " frames have no " + side.other + " frame within " + window +
							" and are left out (as TUM's associate.py does)" });
		}
	}

	// The images of each pair, from their PNG headers.
	for (const auto &[rgb, depth] : pairs) {
		const FrameRef &rgb_ref = p_rgb[rgb];
		const FrameRef &depth_ref = p_depth[depth];
		const std::string rgb_problem = check_rgb_image(join(r_contents->folder, rgb_ref.path), r_contents->rig);
		const std::string depth_problem = check_depth_image(join(r_contents->folder, depth_ref.path), r_contents->rig);
		if (!rgb_problem.empty()) {
			r_contents->issues.push_back({ p_rgb_index, rgb_ref.line, rgb_problem + "; RGB-D frame skipped" });
		}
		if (!depth_problem.empty()) {
			r_contents->issues.push_back({ p_depth_index, depth_ref.line, depth_problem + "; RGB-D frame skipped" });
		}
		if (rgb_problem.empty() && depth_problem.empty()) {
			r_contents->rgbd.push_back(RgbdFrameRef{ rgb_ref, depth_ref });
		}
	}
}

RecordingStatus RecordingReader::open(const std::string &p_folder, const RecordingReadOptions &p_options) {
	close();
	RecordingStatus status;
	std::error_code ec;
	status.error = input_folder_problem(p_folder, "no such recording folder");
	if (!status.error.empty()) {
		return status;
	}
	RecordingContents read;
	read.folder = p_folder;
	// A recording whose writer has not closed it (issue #38: synth killed midway): what its indexes
	// list plays; the reader says why the rest, and the ground truth written at the end, is missing.
	switch (recording_io::writing_state(p_folder)) {
		case recording_io::WritingState::BeingWritten:
			read.issues.push_back({ join(p_folder, recording_io::WRITING_MARKER), 0,
					"a writer is adding to this recording now: the frames its indexes list so far play, later ones are not seen" });
			break;
		case recording_io::WritingState::Abandoned:
			read.issues.push_back({ join(p_folder, recording_io::WRITING_MARKER), 0,
					"the recording was never closed (its writer was stopped midway, or the machine went down): the frames its indexes list "
					"play; what a writer writes on closing (the ground-truth trajectories) is missing" });
			break;
		case recording_io::WritingState::Closed:
			break;
	}

	const RigLoadResult rig = load_rig(join(p_folder, "rig.yaml"));
	if (!rig.ok) {
		status.error = rig.error;
		return status;
	}
	read.rig = rig.rig;

	// room.yaml: without one the recording is SLAM-only (no coarse model, no probes).
	const std::string room_path = join(p_folder, "room.yaml");
	if (fs::exists(room_path, ec)) {
		const RoomLoadResult room = load_room_file(room_path);
		if (!room.ok) {
			status.error = room.error;
			return status;
		}
		read.has_room = true;
		read.room = room.room;
	}

	// The indexes: required, may list no frames; fisheye.txt only when the rig has a fisheye.
	const std::string rgb_index = join(p_folder, "rgb.txt");
	const std::string depth_index = join(p_folder, "depth.txt");
	const std::string fisheye_index = join(p_folder, "fisheye.txt");
	std::vector<FrameRef> rgb;
	std::vector<FrameRef> depth;
	std::vector<FrameRef> fisheye;
	for (const auto &[path, frames] : { std::pair{ &rgb_index, &rgb }, std::pair{ &depth_index, &depth }, std::pair{ &fisheye_index, &fisheye } }) {
		if (frames == &fisheye && !read.rig.has_fisheye() && !fs::exists(fisheye_index, ec)) {
			continue;
		}
		const std::string error = recording_io::read_frame_index(*path, frames, &read.issues);
		if (!error.empty()) {
			status.error = error;
			return status;
		}
	}
	if (!read.rig.has_fisheye() && !fisheye.empty()) {
		read.issues.push_back({ fisheye_index, 0,
				"rig.yaml has no fisheye, so the " + std::to_string(fisheye.size()) + " fisheye frames listed here are left out" });
		fisheye.clear();
	}

	recording_io::pair_and_check_rgbd(rgb, rgb_index, depth, depth_index, p_options.max_rgb_depth_difference_s, false, &read);
	for (const auto &[path, frames] : { std::pair{ &rgb_index, &rgb }, std::pair{ &fisheye_index, &fisheye } }) {
		note_unlikely_frame_spacing(*path, *frames, &read.issues);
	}

	for (const FrameRef &frame : fisheye) {
		const std::string problem = check_fisheye_file(join(p_folder, frame.path), read.rig);
		if (problem.empty()) {
			read.fisheye.push_back(frame);
		} else {
			read.issues.push_back({ fisheye_index, frame.line, problem + "; frame skipped" });
		}
	}

	// Ground truth, optional: a broken file is an issue, not a failure.
	const char *trajectory_files[2] = { "groundtruth/rgb_trajectory.txt", "groundtruth/fisheye_trajectory.txt" };
	for (int stream = 0; stream < 2; stream++) {
		const std::string path = join(p_folder, trajectory_files[stream]);
		if (!fs::exists(path, ec)) {
			continue;
		}
		TrajectoryLoadResult trajectory = load_tum_trajectory(path);
		if (trajectory.ok) {
			read.has_ground_truth[stream] = true;
			read.ground_truth[stream] = std::move(trajectory.trajectory);
		} else {
			read.issues.push_back(recording_io::issue_from_error(path, trajectory.error, "; no ground-truth trajectory"));
		}
	}
	const std::string cubemap_index = join(p_folder, "groundtruth/cubemaps.txt");
	if (fs::exists(cubemap_index, ec)) {
		if (read.has_room) {
			read_cubemap_index(p_folder, cubemap_index, read.room, &read);
		} else {
			read.issues.push_back({ cubemap_index, 0, "the recording has no room.yaml, whose probes the cubemaps are at; no ground-truth cubemaps" });
		}
	}

	const std::string gap_list = join(p_folder, "gaps.txt");
	if (fs::exists(gap_list, ec)) {
		read_gap_list(gap_list, &read);
	}
	const std::string capture_list = join(p_folder, "capture.txt");
	if (fs::exists(capture_list, ec)) {
		read_capture_list(capture_list, &read);
	}

	open_contents(std::move(read));
	status.ok = true;
	return status;
}

void RecordingReader::open_contents(RecordingContents p_contents) {
	contents = std::move(p_contents);
	build_events();
	opened = true;
}

void RecordingReader::close() {
	contents = RecordingContents();
	events.clear();
	opened = false;
}

void RecordingReader::build_events() {
	events.clear();
	events.reserve(contents.rgbd.size() + contents.fisheye.size());
	for (size_t i = 0; i < contents.rgbd.size(); i++) {
		events.push_back(PlaybackEvent{ RecordingStream::Rgbd, i, contents.rgbd[i].rgb.timestamp_s });
	}
	for (size_t i = 0; i < contents.fisheye.size(); i++) {
		events.push_back(PlaybackEvent{ RecordingStream::Fisheye, i, contents.fisheye[i].timestamp_s + contents.rig.fisheye_time_offset_s });
	}
	// Each stream is already in order; a stable sort keeps RGB-D first at equal times.
	std::stable_sort(events.begin(), events.end(), [](const PlaybackEvent &p_a, const PlaybackEvent &p_b) { return p_a.time_s < p_b.time_s; });
}

RgbdFrameResult RecordingReader::read_rgbd(size_t p_index) const {
	RgbdFrameResult result;
	if (p_index >= contents.rgbd.size()) {
		result.error = contents.folder + ": RGB-D frame " + std::to_string(p_index) + " does not exist (" + std::to_string(contents.rgbd.size()) + " frames)";
		return result;
	}
	const RgbdFrameRef &ref = contents.rgbd[p_index];
	const std::string rgb_path = join(contents.folder, ref.rgb.path);
	const std::string depth_path = join(contents.folder, ref.depth.path);
	const Rig &rig = contents.rig;

	cv::Mat rgb;
	std::string error = decode_rgb8(rgb_path, &rgb);
	if (error.empty()) {
		error = size_problem(rgb_path, rgb.cols, rgb.rows, "RGB-D camera", rig.rgb.width, rig.rgb.height);
	}
	if (!error.empty()) {
		result.error = error;
		return result;
	}

	cv::Mat raw;
	error = recording_io::decode_frame_file(depth_path, &raw, nullptr); // 16 bits either way
	if (error.empty() && raw.type() != CV_16UC1) {
		error = depth_path + ": a depth image must be 16-bit single-channel; this decodes as " + recording_io::describe_type(raw.type());
	}
	if (error.empty()) {
		error = size_problem(depth_path, raw.cols, raw.rows, "RGB-D camera", rig.rgb.width, rig.rgb.height);
	}
	if (!error.empty()) {
		result.error = error;
		return result;
	}
	const cv::Mat depth_m = depth_metres_from_raw(raw, rig.depth_scale_m);
	result.frame.timestamp_s = ref.rgb.timestamp_s;
	result.frame.depth_timestamp_s = ref.depth.timestamp_s;
	result.frame.rgb = rgb;
	result.frame.depth_m = depth_m;
	result.frame.capture = capture_of(contents, RecordingStream::Rgbd, ref.rgb.timestamp_s);
	result.ok = true;
	return result;
}

FisheyeFrameResult RecordingReader::read_fisheye(size_t p_index) const {
	FisheyeFrameResult result;
	if (p_index >= contents.fisheye.size()) {
		result.error = contents.folder + ": fisheye frame " + std::to_string(p_index) + " does not exist (" + std::to_string(contents.fisheye.size()) + " frames)";
		return result;
	}
	const FrameRef &ref = contents.fisheye[p_index];
	const std::string path = join(contents.folder, ref.path);
	const std::string extension = lower_extension(path);
	cv::Mat image;
	std::string error;
	bool hdr = false;
	if (extension == ".exr") {
		error = recording_io::read_exr_rgb(path, &image);
		hdr = true;
		if (error.empty()) {
			// NaN or infinite radiance would pass through every stage and score as perfect.
			const cv::Mat values = image.reshape(1);
			// NaN compares false, so |x| < infinity holds exactly for the finite values.
			const int non_finite = int(values.total()) - cv::countNonZero(cv::abs(values) < std::numeric_limits<float>::infinity());
			if (non_finite > 0) {
				error = path + ": " + std::to_string(non_finite) + " channel value" + (non_finite == 1 ? " is" : "s are") +
						" NaN or infinite; an HDR frame must hold finite radiance";
			}
		}
	} else {
		cv::Mat decoded;
		recording_io::FrameFileKind kind = recording_io::FrameFileKind::Png;
		error = recording_io::decode_frame_file(path, &decoded, &kind);
		if (error.empty() && kind == recording_io::FrameFileKind::RawFrame && !fisheye_raw_type(decoded.type())) {
			error = path + ": a fisheye raw frame must be 8-bit gray or R, G, B (HDR frames are EXR files); this is " +
					recording_io::describe_type(decoded.type());
		} else if (error.empty() && kind == recording_io::FrameFileKind::RawFrame) {
			image = decoded; // gray, or stored as R, G, B
		} else if (error.empty() && decoded.depth() != CV_8U) {
			error = path + ": a fisheye PNG must be 8-bit; this decodes as " + recording_io::describe_type(decoded.type());
		} else if (error.empty()) {
			switch (decoded.channels()) {
				case 1:
					image = decoded;
					break;
				case 2:
					cv::extractChannel(decoded, image, 0);
					break;
				case 3:
					cv::cvtColor(decoded, image, cv::COLOR_BGR2RGB);
					break;
				default:
					cv::cvtColor(decoded, image, cv::COLOR_BGRA2RGB);
					break;
			}
		}
	}
	if (error.empty() && contents.rig.fisheye.width > 0) {
		error = size_problem(path, image.cols, image.rows, "fisheye", contents.rig.fisheye.width, contents.rig.fisheye.height);
	}
	if (!error.empty()) {
		result.error = error;
		return result;
	}
	result.frame.timestamp_s = ref.timestamp_s;
	result.frame.image = image;
	result.frame.hdr = hdr;
	result.frame.capture = capture_of(contents, RecordingStream::Fisheye, ref.timestamp_s);
	result.ok = true;
	return result;
}

GroundTruthCubemapResult RecordingReader::ground_truth_cubemap(size_t p_index) const {
	GroundTruthCubemapResult result;
	if (p_index >= contents.cubemaps.size()) {
		result.error = contents.folder + ": ground-truth cubemap " + std::to_string(p_index) + " does not exist (" +
				std::to_string(contents.cubemaps.size()) + " cubemaps)";
		return result;
	}
	const CubemapRef &ref = contents.cubemaps[p_index];
	const std::string path = join(contents.folder, ref.path);
	cv::Mat strip;
	std::string error = recording_io::read_exr_rgb(path, &strip);
	if (error.empty() && strip.rows != 6 * strip.cols) {
		error = path + ": " + size_text(strip.cols, strip.rows) + " pixels is not a cubemap strip (N wide, 6N tall)";
	}
	if (error.empty()) {
		// The truth maps are scored against: a NaN or infinite radiance (issue #38: an all-NaN
		// cubemap once scored as a perfect map) or a negative one is not light.
		const int bad = int(strip.total() * size_t(strip.channels())) - cv::countNonZero((strip.reshape(1) >= 0.0f) & (strip.reshape(1) < std::numeric_limits<float>::infinity()));
		if (bad > 0) {
			error = path + ": " + std::to_string(bad) + " values are NaN, infinite or negative: not a ground-truth radiance";
		}
	}
	if (!error.empty()) {
		result.error = error;
		return result;
	}
	result.cubemap.faces = cubemap_strip_to_faces(strip);

	const std::string ldr_path = fs::path(path).replace_extension(".png").string();
	std::error_code ec;
	if (fs::exists(ldr_path, ec)) {
		cv::Mat ldr;
		error = decode_rgb8(ldr_path, &ldr);
		if (error.empty() && ldr.size() != strip.size()) {
			error = ldr_path + ": " + size_text(ldr.cols, ldr.rows) + " pixels, but its EXR is " + size_text(strip.cols, strip.rows);
		}
		if (!error.empty()) {
			result.error = error;
			return result;
		}
		result.cubemap.ldr_faces = cubemap_strip_to_faces(ldr);
	}
	result.cubemap.timestamp_s = ref.timestamp_s;
	result.cubemap.probe_index = ref.probe_index;
	if (contents.has_room && size_t(ref.probe_index) < contents.room.probes.size()) {
		result.cubemap.position = contents.room.probes[size_t(ref.probe_index)];
	}
	result.ok = true;
	return result;
}

} // namespace roomprobe
