#include "recording_writer.h"

#include <types/cubemap_layout.h>
#include "recording_io.h"
#include "room_file.h"

#include <io/raw_frame.h>


#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

namespace roomprobe {

namespace fs = std::filesystem;
using recording_io::describe_type;
using recording_io::format_number;

namespace {

constexpr const char *TRAJECTORY_FILES[2] = { "groundtruth/rgb_trajectory.txt", "groundtruth/fisheye_trajectory.txt" };

uint64_t file_bytes(const std::string &p_path) {
	std::error_code error;
	const uintmax_t size = std::filesystem::file_size(p_path, error);
	return error ? 0 : uint64_t(size);
}

std::string numbered(const char *p_folder, size_t p_number, const char *p_extension) {
	char name[64];
	std::snprintf(name, sizeof(name), "%s/%06zu%s", p_folder, p_number, p_extension);
	return name;
}

std::string size_text(int p_width, int p_height) {
	return std::to_string(p_width) + "x" + std::to_string(p_height);
}

bool create_folder(const std::string &p_path, std::string *r_error) {
	std::error_code ec;
	fs::create_directories(p_path, ec);
	if (ec || !fs::is_directory(p_path, ec)) {
		*r_error = p_path + ": cannot create the folder" + (ec ? " (" + ec.message() + ")" : std::string());
		return false;
	}
	return true;
}

// Depth in metres (CV_32FC1) or raw units (CV_16UC1) as the 16-bit raw image.
std::string depth_to_raw(const cv::Mat &p_depth, double p_scale_m, const std::string &p_path, cv::Mat *r_raw) {
	if (p_depth.type() == CV_16UC1) {
		*r_raw = p_depth;
		return std::string();
	}
	if (p_depth.type() != CV_32FC1) {
		return p_path + ": depth must be CV_32FC1 metres or CV_16UC1 raw units; got " +
				(p_depth.empty() ? std::string("an empty image") : describe_type(p_depth.type()));
	}
	cv::Mat raw(p_depth.rows, p_depth.cols, CV_16UC1);
	for (int y = 0; y < p_depth.rows; y++) {
		const float *in = p_depth.ptr<float>(y);
		uint16_t *out = raw.ptr<uint16_t>(y);
		for (int x = 0; x < p_depth.cols; x++) {
			const double metres = in[x];
			if (!std::isfinite(metres) || metres <= 0.0) {
				out[x] = 0; // no reading
				continue;
			}
			const double units = std::round(metres / p_scale_m);
			if (units > 65534.0) { // 65535 reads back as "no reading" (depth_metres_from_raw)
				return p_path + ": depth " + format_number(metres) + " m at pixel (" + std::to_string(x) + ", " + std::to_string(y) +
						") is beyond what 16 bits hold at depth_scale_m " + format_number(p_scale_m) + " (" + format_number(65534.0 * p_scale_m) + " m)";
			}
			out[x] = uint16_t(units);
		}
	}
	*r_raw = raw;
	return std::string();
}

// What RecordingWriter::open refuses before touching the folder: the rig, the room and the
// options.
std::string settings_problem(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingWriteOptions &p_options) {
	std::string problem = check_rig(p_rig);
	if (!problem.empty()) {
		return recording_io::join(p_folder, "rig.yaml") + ": " + problem;
	}
	problem = p_room != nullptr ? check_room(*p_room) : std::string();
	if (!problem.empty()) {
		return recording_io::join(p_folder, "room.yaml") + ": " + problem;
	}
	if (p_options.frame_format != FrameFormat::Png && p_options.frame_format != FrameFormat::Zstd) {
		return p_folder + ": unknown frame format " + std::to_string(int(p_options.frame_format));
	}
	problem = p_options.frame_format == FrameFormat::Zstd ? raw_frame_level_problem(p_options.zstd_level) : std::string();
	if (!problem.empty()) {
		return p_folder + ": " + problem + " (RecordingWriteOptions::zstd_level)";
	}
	return std::string();
}

// The claimed folder made ready: found empty (or allowed not to be), a previous recording's files
// that this one may not write removed, the image folders made, and rig.yaml and room.yaml saved.
std::string prepare_folder(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingWriteOptions &p_options) {
	const auto path = [&](const char *p_relative) { return recording_io::join(p_folder, p_relative); };
	std::error_code ec;
	bool empty = true;
	for (const fs::directory_entry &entry : fs::directory_iterator(p_folder, ec)) {
		empty = empty && entry.path().filename() == recording_io::WRITING_MARKER;
	}
	if (ec) {
		return p_folder + ": cannot list the folder (" + ec.message() + ")";
	}
	if (!empty && !p_options.allow_non_empty_folder) {
		return p_folder + ": the folder is not empty; a recording is only written into a new or empty folder "
						  "(nothing was overwritten; RecordingWriteOptions::allow_non_empty_folder overrides this)";
	}
	// Into a used folder (allowed by the options): a previous recording's ground truth, room or
	// fisheye index must not pass for this one's, as it would if this one wrote none.
	for (const char *stale : { TRAJECTORY_FILES[0], TRAJECTORY_FILES[1], "groundtruth/cubemaps.txt", "room.yaml", "fisheye.txt", "capture.txt" }) {
		fs::remove(path(stale), ec);
		if (ec) {
			return path(stale) + ": cannot remove the previous recording's file (" + ec.message() + ")";
		}
	}
	std::string error;
	for (const char *sub : { "rgb", "depth", "fisheye" }) {
		if (std::string(sub) == "fisheye" && !p_rig.has_fisheye()) {
			continue;
		}
		if (!create_folder(path(sub), &error)) {
			return error;
		}
	}
	error = save_rig(path("rig.yaml"), p_rig);
	if (!error.empty()) {
		return error;
	}
	if (p_room != nullptr) {
		error = save_room_file(path("room.yaml"), *p_room);
		if (!error.empty()) {
			return error;
		}
	}
	return std::string();
}

// rgb.txt, depth.txt and fisheye.txt (none without a fisheye) begun with their headers; on a
// failure every one is closed.
std::string open_indexes(const std::string &p_folder, const Rig &p_rig, const RecordingWriteOptions &p_options, std::ofstream *r_rgb_index,
		std::ofstream *r_depth_index, std::ofstream *r_fisheye_index) {
	struct Index {
		std::ofstream *stream;
		const char *name;
		const char *header;
	};
	const bool raw = p_options.frame_format == FrameFormat::Zstd;
	const std::string rgb_header = std::string("# RoomProbe recording: RGB images (") + (raw ? "8-bit R, G, B raw frames, zstd" : "8-bit RGB PNG") +
			"), RGB-D camera clock\n# timestamp_s filename\n";
	const std::string depth_header = std::string("# RoomProbe recording: depth images (") + (raw ? "16-bit raw frames, zstd" : "16-bit PNG") +
			", value x rig depth_scale_m = metres, 0 = no reading), RGB-D camera clock\n# timestamp_s filename\n";
	const std::string fisheye_header = std::string("# RoomProbe recording: fisheye images (") + (raw ? "8-bit raw frames, zstd," : "8-bit PNG") +
			" or linear HDR EXR), fisheye camera clock\n# timestamp_s filename\n";
	const Index indexes[3] = {
		{ r_rgb_index, "rgb.txt", rgb_header.c_str() },
		{ r_depth_index, "depth.txt", depth_header.c_str() },
		{ r_fisheye_index, "fisheye.txt", fisheye_header.c_str() },
	};
	for (const Index &index : indexes) {
		index.stream->close();
		index.stream->clear();
		if (index.stream == r_fisheye_index && !p_rig.has_fisheye()) {
			continue; // an RGB-D camera alone: no fisheye.txt
		}
		index.stream->open(recording_io::join(p_folder, index.name), std::ios::out | std::ios::trunc | std::ios::binary);
		*index.stream << index.header;
		index.stream->flush();
		if (!*index.stream) {
			for (const Index &other : indexes) {
				other.stream->close();
			}
			return recording_io::join(p_folder, index.name) + ": cannot be written";
		}
	}
	return std::string();
}

} // namespace

const char *frame_format_name(FrameFormat p_format) {
	return p_format == FrameFormat::Png ? "png" : "zstd";
}

bool parse_frame_format(const std::string &p_text, FrameFormat *r_format) {
	if (p_text == "zstd" || p_text == "png") {
		*r_format = p_text == "png" ? FrameFormat::Png : FrameFormat::Zstd;
		return true;
	}
	return false;
}

RecordingWriter::~RecordingWriter() {
	close();
}

RecordingStatus RecordingWriter::fail(std::string p_error) const {
	RecordingStatus status;
	status.error = std::move(p_error);
	return status;
}

std::string RecordingWriter::path(const std::string &p_relative) const {
	return recording_io::join(folder, p_relative);
}

std::string RecordingWriter::append_line(std::ofstream &p_index, const std::string &p_index_name, const std::string &p_line) {
	p_index << p_line << '\n';
	p_index.flush();
	if (!p_index) {
		return path(p_index_name) + ": write failed";
	}
	return std::string();
}

// One line of capture.txt for a frame that carries what its device said (live recordings);
// the file is started with the first such frame.
std::string RecordingWriter::append_capture(RecordingStream p_stream, double p_timestamp_s, const CaptureInfo &p_capture) {
	if (!p_capture.is_known()) {
		return std::string();
	}
	if (!capture_index.is_open()) {
		capture_index.clear();
		capture_index.open(path("capture.txt"), std::ios::out | std::ios::trunc | std::ios::binary);
		capture_index << "# RoomProbe recording: what the live devices said about each frame (nan: not reported)\n"
						 "# stream timestamp_s device_time_s device_frame_id exposure_us gain\n";
		if (!capture_index) {
			return path("capture.txt") + ": cannot be written";
		}
	}
	const auto number = [](double p_value) { return std::isnan(p_value) ? std::string("nan") : format_number(p_value); };
	return append_line(capture_index, "capture.txt", std::string(recording_stream_name(p_stream)) + " " + format_number(p_timestamp_s) + " " +
					number(p_capture.device_time_s) + " " + std::to_string(p_capture.device_frame_id) + " " + number(p_capture.exposure_us) + " " +
					number(p_capture.gain));
}

RecordingStatus RecordingWriter::open(const std::string &p_folder, const Rig &p_rig, const RoomInfo &p_room, const RecordingWriteOptions &p_options) {
	return open_folder(p_folder, p_rig, &p_room, p_options);
}

RecordingStatus RecordingWriter::open_without_room(const std::string &p_folder, const Rig &p_rig, const RecordingWriteOptions &p_options) {
	return open_folder(p_folder, p_rig, nullptr, p_options);
}

RecordingStatus RecordingWriter::open_folder(const std::string &p_folder, const Rig &p_rig, const RoomInfo *p_room, const RecordingWriteOptions &p_options) {
	if (opened) {
		return fail(p_folder + ": this writer is already writing " + folder + "; close() it first");
	}
	folder = p_folder;
	std::string problem = settings_problem(p_folder, p_rig, p_room, p_options);
	if (!problem.empty()) {
		return fail(problem);
	}
	std::error_code ec;
	if (fs::exists(p_folder, ec) && !fs::is_directory(p_folder, ec)) {
		return fail(p_folder + ": exists and is not a folder");
	}
	std::string error;
	if (!create_folder(p_folder, &error)) {
		return fail(error);
	}
	// One writer a folder (issue #38): the marker is claimed before the folder is found empty, so
	// that of two writers started together, one is refused, and never do their frames mix.
	problem = claim_folder(p_folder);
	if (!problem.empty()) {
		return fail(problem);
	}
	struct ReleaseUnlessOpened {
		RecordingWriter *writer;
		~ReleaseUnlessOpened() {
			if (!writer->opened) {
				writer->release_claim(writer->claim_made);
			}
		}
	} release{ this };
	error = prepare_folder(p_folder, p_rig, p_room, p_options);
	if (!error.empty()) {
		return fail(error);
	}
	error = open_indexes(p_folder, p_rig, p_options, &rgb_index, &depth_index, &fisheye_index);
	if (!error.empty()) {
		return fail(error);
	}
	rig = p_rig;
	has_room = p_room != nullptr;
	room = has_room ? *p_room : RoomInfo();
	options = p_options;
	rgbd_count = 0;
	image_bytes = 0;
	fisheye_count = 0;
	cubemap_count = 0;
	has_rgb_time = false;
	has_fisheye_time = false;
	has_cubemap_time = false;
	ground_truth[0].clear();
	ground_truth[1].clear();
	opened = true;
	RecordingStatus status;
	status.ok = true;
	return status;
}

RecordingStatus RecordingWriter::add_rgbd(const RgbdFrame &p_frame) {
	if (!opened) {
		return fail("RecordingWriter::add_rgbd: no recording is open");
	}
	const bool raw_frames = options.frame_format == FrameFormat::Zstd;
	const char *extension = raw_frames ? ".zst" : ".png";
	const std::string rgb_name = numbered("rgb", rgbd_count, extension);
	const std::string depth_name = numbered("depth", rgbd_count, extension);
	const std::string rgb_path = path(rgb_name);
	const std::string depth_path = path(depth_name);
	const double rgb_time = p_frame.timestamp_s;
	const double depth_time = std::isnan(p_frame.depth_timestamp_s) ? rgb_time : p_frame.depth_timestamp_s;
	if (!std::isfinite(rgb_time) || !std::isfinite(depth_time)) {
		return fail(path("rgb.txt") + ": the frame's timestamps must be finite (got " + format_number(rgb_time) + ", depth " + format_number(depth_time) + ")");
	}
	if (has_rgb_time && !(rgb_time > last_rgb_time_s)) {
		return fail(path("rgb.txt") + ": timestamp " + format_number(rgb_time) + " is not after the previous frame's " + format_number(last_rgb_time_s));
	}
	if (has_rgb_time && !(depth_time > last_depth_time_s)) {
		return fail(path("depth.txt") + ": timestamp " + format_number(depth_time) + " is not after the previous frame's " + format_number(last_depth_time_s));
	}
	if (p_frame.rgb.type() != CV_8UC3) {
		return fail(rgb_path + ": the RGB image must be CV_8UC3 (R, G, B); got " +
				(p_frame.rgb.empty() ? std::string("an empty image") : describe_type(p_frame.rgb.type())));
	}
	if (p_frame.rgb.cols != rig.rgb.width || p_frame.rgb.rows != rig.rgb.height) {
		return fail(rgb_path + ": the RGB image is " + size_text(p_frame.rgb.cols, p_frame.rgb.rows) + ", the rig's RGB-D camera " +
				size_text(rig.rgb.width, rig.rgb.height));
	}
	if (p_frame.depth_m.cols != rig.rgb.width || p_frame.depth_m.rows != rig.rgb.height) {
		return fail(depth_path + ": the depth image is " + size_text(p_frame.depth_m.cols, p_frame.depth_m.rows) +
				", the rig's RGB-D camera (depth is registered to it) " + size_text(rig.rgb.width, rig.rgb.height));
	}
	cv::Mat raw;
	std::string error = depth_to_raw(p_frame.depth_m, rig.depth_scale_m, depth_path, &raw);
	if (!error.empty()) {
		return fail(error);
	}
	if (raw_frames) {
		error = raw_frame_write(rgb_path, p_frame.rgb, options.zstd_level); // stored as R, G, B
		if (error.empty()) {
			error = raw_frame_write(depth_path, raw, options.zstd_level);
		}
	} else {
		cv::Mat bgr;
		cv::cvtColor(p_frame.rgb, bgr, cv::COLOR_RGB2BGR);
		error = recording_io::write_png(rgb_path, bgr);
		if (error.empty()) {
			error = recording_io::write_png(depth_path, raw);
		}
	}
	if (error.empty()) {
		error = append_line(rgb_index, "rgb.txt", format_number(rgb_time) + " " + rgb_name);
	}
	if (error.empty()) {
		error = append_line(depth_index, "depth.txt", format_number(depth_time) + " " + depth_name);
	}
	if (error.empty()) {
		error = append_capture(RecordingStream::Rgbd, rgb_time, p_frame.capture);
	}
	if (!error.empty()) {
		return fail(error);
	}
	image_bytes += file_bytes(rgb_path) + file_bytes(depth_path);
	has_rgb_time = true;
	last_rgb_time_s = rgb_time;
	last_depth_time_s = depth_time;
	rgbd_count++;
	RecordingStatus status;
	status.ok = true;
	return status;
}

RecordingStatus RecordingWriter::add_fisheye(const FisheyeFrame &p_frame) {
	if (!opened) {
		return fail("RecordingWriter::add_fisheye: no recording is open");
	}
	if (!rig.has_fisheye()) {
		return fail(path("fisheye.txt") + ": the rig has no fisheye (an RGB-D camera alone), so the recording takes no fisheye frames");
	}
	const cv::Mat &image = p_frame.image;
	const bool hdr_type = image.type() == CV_32FC3;
	const bool ldr_type = image.type() == CV_8UC1 || image.type() == CV_8UC3;
	const bool raw_frames = options.frame_format == FrameFormat::Zstd;
	const std::string name = numbered("fisheye", fisheye_count, hdr_type ? ".exr" : raw_frames ? ".zst" : ".png");
	const std::string file = path(name);
	if (!std::isfinite(p_frame.timestamp_s)) {
		return fail(path("fisheye.txt") + ": the frame's timestamp must be finite (got " + format_number(p_frame.timestamp_s) + ")");
	}
	if (has_fisheye_time && !(p_frame.timestamp_s > last_fisheye_time_s)) {
		return fail(path("fisheye.txt") + ": timestamp " + format_number(p_frame.timestamp_s) + " is not after the previous frame's " +
				format_number(last_fisheye_time_s));
	}
	const std::string problem = check_fisheye_image(p_frame, rig.fisheye.width, rig.fisheye.height);
	if (!problem.empty()) {
		return fail(file + ": " + problem + (ldr_type || hdr_type || image.empty() ? "" : "; got " + describe_type(image.type())));
	}
	std::string error;
	if (hdr_type) {
		error = recording_io::write_exr_rgb(file, image, options.exr_full_float);
	} else if (raw_frames) {
		error = raw_frame_write(file, image, options.zstd_level); // gray, or stored as R, G, B
	} else if (image.channels() == 3) {
		cv::Mat bgr;
		cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
		error = recording_io::write_png(file, bgr);
	} else {
		error = recording_io::write_png(file, image);
	}
	if (error.empty()) {
		error = append_line(fisheye_index, "fisheye.txt", format_number(p_frame.timestamp_s) + " " + name);
	}
	if (error.empty()) {
		error = append_capture(RecordingStream::Fisheye, p_frame.timestamp_s, p_frame.capture);
	}
	if (!error.empty()) {
		return fail(error);
	}
	image_bytes += file_bytes(file);
	has_fisheye_time = true;
	last_fisheye_time_s = p_frame.timestamp_s;
	fisheye_count++;
	RecordingStatus status;
	status.ok = true;
	return status;
}

RecordingStatus RecordingWriter::add_ground_truth_pose(RecordingStream p_stream, double p_t_s, const Pose &p_world_from_camera) {
	const int stream = int(p_stream);
	if (!opened) {
		return fail("RecordingWriter::add_ground_truth_pose: no recording is open");
	}
	if (stream < 0 || stream > 1) {
		return fail("RecordingWriter::add_ground_truth_pose: unknown stream " + std::to_string(stream));
	}
	std::string error;
	if (!ground_truth[stream].append(TimedPose{ p_t_s, p_world_from_camera }, &error)) {
		return fail(path(TRAJECTORY_FILES[stream]) + ": " + error);
	}
	RecordingStatus status;
	status.ok = true;
	return status;
}

RecordingStatus RecordingWriter::add_ground_truth_cubemap(double p_t_s, int p_probe_index, const CubemapFaces &p_faces, const CubemapFaces &p_ldr_faces) {
	if (!opened) {
		return fail("RecordingWriter::add_ground_truth_cubemap: no recording is open");
	}
	const std::string index_path = path("groundtruth/cubemaps.txt");
	const std::string name = numbered("groundtruth/cubemaps", cubemap_count, ".exr");
	const std::string ldr_name = numbered("groundtruth/cubemaps", cubemap_count, ".png");
	const std::string file = path(name);
	if (!std::isfinite(p_t_s)) {
		return fail(index_path + ": the cubemap's timestamp must be finite (got " + format_number(p_t_s) + ")");
	}
	if (has_cubemap_time && p_t_s < last_cubemap_time_s) {
		return fail(index_path + ": timestamp " + format_number(p_t_s) + " is before the previous cubemap's " + format_number(last_cubemap_time_s));
	}
	if (!has_room) {
		return fail(index_path + ": the recording has no room, and ground-truth cubemaps are at the room's probes");
	}
	if (p_probe_index < 0 || size_t(p_probe_index) >= room.probes.size()) {
		return fail(index_path + ": probe index " + std::to_string(p_probe_index) + " is not one of the room's " + std::to_string(room.probes.size()) + " probes");
	}
	if (p_faces[0].type() != CV_32FC3) {
		return fail(file + ": cubemap faces must be CV_32FC3 (linear R, G, B); got " +
				(p_faces[0].empty() ? std::string("an empty face") : describe_type(p_faces[0].type())));
	}
	const cv::Mat strip = cubemap_faces_to_strip(p_faces);
	if (strip.empty()) {
		return fail(file + ": the six cubemap faces must be square, all the same size and type");
	}
	bool has_ldr = false;
	for (const cv::Mat &face : p_ldr_faces) {
		has_ldr = has_ldr || !face.empty();
	}
	cv::Mat ldr_strip;
	if (has_ldr) {
		ldr_strip = cubemap_faces_to_strip(p_ldr_faces);
		if (ldr_strip.empty() || ldr_strip.type() != CV_8UC3 || ldr_strip.size() != strip.size()) {
			return fail(path(ldr_name) + ": the 8-bit faces must be six CV_8UC3 (R, G, B) faces the size of the HDR ones (" +
					size_text(strip.cols, strip.cols) + ")");
		}
	}
	std::string error;
	if (!create_folder(path("groundtruth/cubemaps"), &error)) {
		return fail(error);
	}
	error = recording_io::write_exr_rgb(file, strip, options.exr_full_float);
	if (error.empty() && has_ldr) {
		cv::Mat bgr;
		cv::cvtColor(ldr_strip, bgr, cv::COLOR_RGB2BGR);
		error = recording_io::write_png(path(ldr_name), bgr);
	}
	if (error.empty() && !cubemap_index.is_open()) {
		cubemap_index.clear();
		cubemap_index.open(index_path, std::ios::out | std::ios::trunc | std::ios::binary);
		cubemap_index << "# RoomProbe recording: ground-truth cubemaps (EXR, N x 6N strip +X -X +Y -Y +Z -Z), RGB-D camera clock\n"
						 "# timestamp_s probe_index filename\n";
		if (!cubemap_index) {
			error = index_path + ": cannot be written";
		}
	}
	if (error.empty()) {
		error = append_line(cubemap_index, "groundtruth/cubemaps.txt", format_number(p_t_s) + " " + std::to_string(p_probe_index) + " " + name);
	}
	if (!error.empty()) {
		return fail(error);
	}
	has_cubemap_time = true;
	last_cubemap_time_s = p_t_s;
	cubemap_count++;
	RecordingStatus status;
	status.ok = true;
	return status;
}

RecordingStatus RecordingWriter::close() {
	RecordingStatus status;
	status.ok = true;
	if (!opened) {
		return status;
	}
	std::string error;
	for (int stream = 0; stream < 2; stream++) {
		if (ground_truth[stream].is_empty()) {
			continue;
		}
		std::string problem;
		if (create_folder(path("groundtruth"), &problem)) {
			problem = save_tum_trajectory(path(TRAJECTORY_FILES[stream]), ground_truth[stream]);
		}
		if (error.empty()) {
			error = problem;
		}
		ground_truth[stream].clear();
	}
	struct Index {
		std::ofstream *stream;
		const char *name;
	};
	const Index indexes[5] = { { &rgb_index, "rgb.txt" }, { &depth_index, "depth.txt" }, { &fisheye_index, "fisheye.txt" },
		{ &cubemap_index, "groundtruth/cubemaps.txt" }, { &capture_index, "capture.txt" } };
	for (const Index &index : indexes) {
		if (!index.stream->is_open()) {
			continue;
		}
		index.stream->close();
		if (!*index.stream && error.empty()) {
			error = path(index.name) + ": write failed on closing";
		}
		index.stream->clear();
	}
	opened = false;
	release_claim(true); // closed: the marker goes (a killed writer leaves it behind)
	if (!error.empty()) {
		status.ok = false;
		status.error = error;
	}
	return status;
}

std::string RecordingWriter::claim_folder(const std::string &p_folder) {
	const std::string marker = recording_io::join(p_folder, recording_io::WRITING_MARKER);
	claim_made = false;
	int fd = ::open(marker.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
	if (fd >= 0) {
		claim_made = true;
	} else if (errno == EEXIST) { // left by a writer that was killed, or held by one that writes now
		fd = ::open(marker.c_str(), O_RDWR | O_CLOEXEC);
	}
	if (fd < 0) {
		return marker + ": cannot be made (" + std::strerror(errno) + ")";
	}
	// An open file description's lock: another writer conflicts whether it is another process or
	// this one, and the system lets go of it when the process dies.
	struct flock lock {};
	lock.l_type = F_WRLCK;
	lock.l_whence = SEEK_SET;
	if (::fcntl(fd, F_OFD_SETLK, &lock) != 0) {
		const int why = errno;
		::close(fd);
		claim_made = false; // another's now: never removed by this writer
		if (why == EAGAIN || why == EACCES) {
			return p_folder + ": another writer is recording into this folder now (it holds " + recording_io::WRITING_MARKER + "); nothing written";
		}
		return marker + ": cannot be locked (" + std::strerror(why) + ")";
	}
	const std::string owner = "pid " + std::to_string(::getpid()) + "\n";
	if (::ftruncate(fd, 0) != 0 || ::write(fd, owner.data(), owner.size()) != ssize_t(owner.size())) {
		// Only for people reading it: the lock is what counts.
	}
	claim = fd;
	return "";
}

void RecordingWriter::release_claim(bool p_remove) {
	if (claim < 0) {
		return;
	}
	if (p_remove) {
		::unlink(recording_io::join(folder, recording_io::WRITING_MARKER).c_str());
	}
	::close(claim);
	claim = -1;
	claim_made = false;
}

} // namespace roomprobe
