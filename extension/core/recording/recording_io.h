#pragma once
// Internal helpers shared by the recording reader, writer and the TUM reader: index files,
// PNG checks and decoding, raw frame files, EXR files, timestamp association. Not an API for the
// rest of the core: include recording_reader.h, recording_writer.h or tum_dataset.h instead.
//
// Nothing here throws. Functions returning a std::string return an error (empty on success)
// that names the file; check_png_bytes, which has no file, says only what is wrong.

#include "recording_types.h"

#include <io/opencv.h>
#include <io/raw_frame.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace roomprobe::recording_io {

// Shortest text that reads back as the same double, in fixed notation ("0.1", "1305031102.175304").
std::string format_number(double p_value);
// Locale-independent: the whole of p_text must be a finite number.
bool parse_number(std::string_view p_text, double *r_value);
bool parse_int(std::string_view p_text, int *r_value);

// The file a RecordingWriter keeps in its folder while the recording is open, locked (an open file
// description lock) while its writer lives, and removes when the recording is closed (issue #38):
// a second writer into the same folder is refused, and a recording whose writer was killed is
// known by the marker left behind.
inline constexpr const char *WRITING_MARKER = ".roomprobe-writing";
enum class WritingState {
	Closed, // no marker: the writer closed the recording
	BeingWritten, // the marker is locked: a writer is adding to it now
	Abandoned, // the marker without its lock: the writer stopped (killed) before closing it
};
WritingState writing_state(const std::string &p_folder);

// p_relative joined onto p_folder, as a path string for messages and opening.
std::string join(const std::filesystem::path &p_folder, const std::string &p_relative);

// Why p_path cannot be read as a file, naming it: "missing", "a folder, not a file" or "not a
// regular file" (a folder where an index should be was once called missing).
std::string not_a_file_error(const std::string &p_path);

// "8-bit 3-channel", "16-bit 1-channel", "32-bit float 3-channel", for messages.
std::string describe_type(int p_cv_type);

// The lines of a text index that are not blank and not '#' comments, trimmed.
struct IndexLine {
	int line = 0; // 1-based
	std::string text;
};
std::string read_index_lines(const std::string &p_path, std::vector<IndexLine> *r_lines);

// "" when an index's path stays inside its recording, else what is wrong with it ("'../x' leaves
// the recording folder ..."): absolute paths and paths climbing out are refused, for every index.
std::string path_leaves_recording(const std::string &p_path);

// Reads a frame index, 'timestamp_s relative/path' a line. Lines that do not parse, absolute
// paths and timestamps that do not increase become issues and are skipped (a timestamp is
// compared with the last accepted one). Only an unreadable file is an error.
std::string read_frame_index(const std::string &p_path, std::vector<FrameRef> *r_frames, std::vector<RecordingIssue> *r_issues);

// The header of a PNG (IHDR) and whether it is complete.
struct PngInfo {
	int width = 0;
	int height = 0;
	int bit_depth = 0; // 1, 2, 4, 8 or 16
	int color_type = 0; // 0 gray, 2 RGB, 3 palette, 4 gray + alpha, 6 RGBA
};
// Reads the signature and IHDR, and checks that the file ends with its IEND chunk (so a file cut
// short is caught without decoding it). Errors: missing, not a PNG, truncated.
std::string read_png_info(const std::string &p_path, PngInfo *r_info);
// The chunks of a PNG held in memory, walked to IEND: "" or why it is not a complete PNG.
std::string check_png_bytes(const std::vector<uint8_t> &p_bytes);
// The frame header of a JPEG (its SOFn segment).
struct JpegInfo {
	int width = 0;
	int height = 0;
	int components = 0; // 1 gray, 3 colour (YCbCr), 4 CMYK
};
// True for a path ending in .jpg or .jpeg (any case): colour images some datasets store so.
bool is_jpeg_path(const std::string &p_path);
// Reads the markers up to the frame header (SOFn) and checks that an end-of-image marker (EOI)
// closes the file, so that a file cut short is caught without decoding it. Errors: missing, not
// a JPEG, truncated, corrupt.
std::string read_jpeg_info(const std::string &p_path, JpegInfo *r_info);
// Reads and decodes a JPEG (BGR or gray, as cv::imdecode gives it) after those checks.
std::string decode_jpeg(const std::string &p_path, cv::Mat *r_image);
// Writes a PNG (BGR or gray, as cv::imwrite takes it).
std::string write_png(const std::string &p_path, const cv::Mat &p_image);

// A frame image file of a recording, told apart by its first bytes: a PNG or a raw frame file
// (io/raw_frame.h: zstd-compressed samples, colour as R, G, B).
enum class FrameFileKind {
	Png,
	RawFrame,
};
struct FrameFileInfo {
	FrameFileKind kind = FrameFileKind::Png;
	int width = 0;
	int height = 0;
	PngInfo png; // kind Png
	RawFrameHeader raw; // kind RawFrame
};
// Reads a frame file's header and checks that the file is complete, without decoding it: a PNG
// as read_png_info does; a raw frame's header, and a length that is the header's. Errors:
// missing, neither a PNG nor a raw frame, truncated, a corrupt header.
std::string read_frame_file_info(const std::string &p_path, FrameFileInfo *r_info);
// Reads and decodes a PNG (cv::IMREAD_UNCHANGED: B, G, R, 16 bits kept; checked complete first)
// or a raw frame file (the samples as stored: R, G, B; io/raw_frame.h writes them), chosen by its
// first bytes; *r_kind (when not null) says which. Errors: missing, unreadable, neither,
// truncated, corrupt.
std::string decode_frame_file(const std::string &p_path, cv::Mat *r_image, FrameFileKind *r_kind);

// Writes a CV_32FC3 R, G, B image as an EXR with R, G, B channels (half, or float), ZIP
// compressed. Values must be finite (and within half's range when half). Replaces p_path whole or
// leaves it as it was (io/replace_file.h).
std::string write_exr_rgb(const std::string &p_path, const cv::Mat &p_rgb, bool p_full_float);
// The data window size of an EXR, from its header only.
std::string read_exr_size(const std::string &p_path, int *r_width, int *r_height);
// Reads the R, G, B channels of an EXR (any pixel type) into CV_32FC3.
std::string read_exr_rgb(const std::string &p_path, cv::Mat *r_rgb);

// An error "<p_path>:<line>: problem" (as load_tum_trajectory gives) as an issue with that file
// and line, p_suffix appended to the message.
RecordingIssue issue_from_error(const std::string &p_path, const std::string &p_error, const std::string &p_suffix);

// Pairs two sorted timestamp lists as TUM's associate.py does: every pair closer than
// p_max_difference_s is a candidate; candidates are taken closest first, each timestamp used
// once; the pairs come out in time order. r_pairs holds (index in a, index in b).
void associate(const std::vector<double> &p_a, const std::vector<double> &p_b, double p_max_difference_s,
		std::vector<std::pair<size_t, size_t>> *r_pairs);

} // namespace roomprobe::recording_io
