#include "recording_io.h"
#include <io/image_codec.h>
#include <io/exr_write.h>
#include <io/input_path.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImathBox.h>
#include <half.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <system_error>
#include <tuple>

#include <fcntl.h>
#include <unistd.h>

namespace roomprobe {

namespace recording_io {

namespace fs = std::filesystem;

namespace {

constexpr uint8_t PNG_SIGNATURE[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' };
// An IEND chunk: length 0, type, CRC. Every complete PNG ends with these 12 bytes.
constexpr uint8_t PNG_IEND[12] = { 0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82 };
constexpr size_t PNG_HEADER_SIZE = 8 + 8 + 13 + 4; // signature, IHDR chunk

uint32_t read_be32(const uint8_t *p_bytes) {
	return (uint32_t(p_bytes[0]) << 24) | (uint32_t(p_bytes[1]) << 16) | (uint32_t(p_bytes[2]) << 8) | uint32_t(p_bytes[3]);
}

std::string_view trim(std::string_view p_text) {
	const char *space = " \t\r\n\v\f";
	const size_t first = p_text.find_first_not_of(space);
	if (first == std::string_view::npos) {
		return std::string_view();
	}
	const size_t last = p_text.find_last_not_of(space);
	return p_text.substr(first, last - first + 1);
}

bool file_exists(const std::string &p_path) {
	std::error_code error;
	return fs::is_regular_file(p_path, error);
}

// Checks the signature and IHDR of the first PNG_HEADER_SIZE bytes.
std::string parse_png_header(const uint8_t *p_bytes, size_t p_size, PngInfo *r_info) {
	if (p_size < 8 || std::memcmp(p_bytes, PNG_SIGNATURE, 8) != 0) {
		return "not a PNG file (no PNG signature)";
	}
	if (p_size < PNG_HEADER_SIZE) {
		return "truncated: the PNG ends inside its header";
	}
	if (read_be32(p_bytes + 8) != 13 || std::memcmp(p_bytes + 12, "IHDR", 4) != 0) {
		return "corrupt PNG: no IHDR chunk after the signature";
	}
	PngInfo info;
	info.width = int(std::min<uint32_t>(read_be32(p_bytes + 16), 0x7fffffff));
	info.height = int(std::min<uint32_t>(read_be32(p_bytes + 20), 0x7fffffff));
	info.bit_depth = p_bytes[24];
	info.color_type = p_bytes[25];
	if (info.width == 0 || info.height == 0) {
		return "corrupt PNG: zero width or height";
	}
	*r_info = info;
	return std::string();
}

// Walks the chunks from the signature to IEND; p_read(offset, 8 bytes) gives a chunk header.
template <class ReadHeader>
std::string walk_png_chunks(uint64_t p_size, ReadHeader p_read) {
	uint64_t offset = 8;
	while (true) {
		uint8_t header[8];
		if (offset + 8 > p_size || !p_read(offset, header)) {
			return "truncated: the PNG ends at byte " + std::to_string(p_size) + ", before its IEND chunk";
		}
		const uint64_t length = read_be32(header);
		const std::string type(reinterpret_cast<const char *>(header + 4), 4);
		// A damaged length or type is corruption, not a file cut short: chunk types are four
		// ASCII letters, and lengths are below 2^31 (PNG specification, 5.3).
		if (!std::all_of(type.begin(), type.end(), [](char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; })) {
			return "corrupt PNG: the chunk at byte " + std::to_string(offset) + " has no valid type";
		}
		if (length > 0x7fffffffu) {
			return "corrupt PNG: chunk '" + type + "' at byte " + std::to_string(offset) + " claims " + std::to_string(length) +
					" bytes, above PNG's limit of 2^31 - 1";
		}
		const uint64_t end = offset + 8 + length + 4;
		if (end > p_size) {
			return "truncated: the PNG ends at byte " + std::to_string(p_size) + ", inside a chunk ('" + type + "') that needs " +
					std::to_string(end) + " bytes";
		}
		if (std::memcmp(header + 4, "IEND", 4) == 0) {
			return std::string();
		}
		offset = end;
	}
}

template <class Function>
std::string catch_all(const std::string &p_path, Function p_function) {
	try {
		return p_function();
	} catch (const std::exception &e) {
		return p_path + ": " + e.what();
	} catch (...) {
		return p_path + ": unknown error";
	}
}

std::string read_whole_file(const std::string &p_path, std::vector<uint8_t> *r_bytes) {
	if (!file_exists(p_path)) {
		return not_a_file_error(p_path);
	}
	return read_file_bytes(p_path, r_bytes);
}

} // namespace

// The largest HDR image read: 2^26 pixels, 768 MB as float RGB (a damaged or hostile header's
// size is refused before anything is allocated).
constexpr int64_t EXR_MAX_PIXELS = int64_t(1) << 26;

WritingState writing_state(const std::string &p_folder) {
	const int fd = ::open(join(p_folder, WRITING_MARKER).c_str(), O_RDONLY | O_CLOEXEC);
	if (fd < 0) {
		return WritingState::Closed;
	}
	// Asked, never taken: a writer starting now is not refused because of this look.
	struct flock lock {};
	lock.l_type = F_WRLCK;
	lock.l_whence = SEEK_SET;
	const bool held = ::fcntl(fd, F_OFD_GETLK, &lock) == 0 && lock.l_type != F_UNLCK;
	::close(fd);
	return held ? WritingState::BeingWritten : WritingState::Abandoned;
}

std::string not_a_file_error(const std::string &p_path) {
	const std::string problem = input_file_problem(p_path);
	return problem.empty() ? p_path + ": cannot be read" : problem; // a regular file that could not be read after all
}

std::string format_number(double p_value) {
	char buffer[512];
	const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), p_value, std::chars_format::fixed);
	if (result.ec != std::errc()) {
		const std::to_chars_result general = std::to_chars(buffer, buffer + sizeof(buffer), p_value);
		return std::string(buffer, general.ptr);
	}
	return std::string(buffer, result.ptr);
}

bool parse_number(std::string_view p_text, double *r_value) {
	p_text = trim(p_text);
	if (p_text.empty()) {
		return false;
	}
	double value = 0.0;
	const std::from_chars_result result = std::from_chars(p_text.data(), p_text.data() + p_text.size(), value);
	if (result.ec != std::errc() || result.ptr != p_text.data() + p_text.size() || !std::isfinite(value)) {
		return false;
	}
	*r_value = value;
	return true;
}

bool parse_int(std::string_view p_text, int *r_value) {
	p_text = trim(p_text);
	if (p_text.empty()) {
		return false;
	}
	int value = 0;
	const std::from_chars_result result = std::from_chars(p_text.data(), p_text.data() + p_text.size(), value);
	if (result.ec != std::errc() || result.ptr != p_text.data() + p_text.size()) {
		return false;
	}
	*r_value = value;
	return true;
}

std::string join(const fs::path &p_folder, const std::string &p_relative) {
	if (p_folder.empty()) {
		return p_relative;
	}
	return (p_folder / p_relative).string();
}

std::string describe_type(int p_cv_type) {
	const int depth = CV_MAT_DEPTH(p_cv_type);
	const int channels = CV_MAT_CN(p_cv_type);
	std::string bits;
	switch (depth) {
		case CV_8U:
		case CV_8S:
			bits = "8-bit";
			break;
		case CV_16U:
		case CV_16S:
			bits = "16-bit";
			break;
		case CV_16F:
			bits = "16-bit float";
			break;
		case CV_32S:
			bits = "32-bit integer";
			break;
		case CV_32F:
			bits = "32-bit float";
			break;
		case CV_64F:
			bits = "64-bit float";
			break;
		default:
			bits = "unknown-depth";
			break;
	}
	return bits + " " + std::to_string(channels) + "-channel";
}

std::string read_index_lines(const std::string &p_path, std::vector<IndexLine> *r_lines) {
	r_lines->clear();
	if (!file_exists(p_path)) {
		return not_a_file_error(p_path);
	}
	std::ifstream file(p_path, std::ios::binary);
	if (!file) {
		return p_path + ": cannot be opened for reading";
	}
	std::string text;
	int number = 0;
	while (std::getline(file, text)) {
		number++;
		const std::string_view line = trim(text);
		if (line.empty() || line.front() == '#') {
			continue;
		}
		r_lines->push_back(IndexLine{ number, std::string(line) });
	}
	if (file.bad()) {
		return p_path + ": read error after line " + std::to_string(number);
	}
	return std::string();
}

std::string path_leaves_recording(const std::string &p_path) {
	if (fs::path(p_path).is_absolute()) {
		return "'" + p_path + "' is an absolute path; paths are relative to the recording folder";
	}
	const fs::path normal = fs::path(p_path).lexically_normal();
	if (normal.empty() || *normal.begin() == ".." || normal == ".") {
		return "'" + p_path + "' leaves the recording folder; paths stay inside it";
	}
	return "";
}

std::string read_frame_index(const std::string &p_path, std::vector<FrameRef> *r_frames, std::vector<RecordingIssue> *r_issues) {
	r_frames->clear();
	std::vector<IndexLine> lines;
	const std::string error = read_index_lines(p_path, &lines);
	if (!error.empty()) {
		return error;
	}
	for (const IndexLine &line : lines) {
		const std::string_view text = line.text;
		const size_t space = text.find_first_of(" \t");
		const std::string_view path = space == std::string_view::npos ? std::string_view() : trim(text.substr(space));
		const std::string_view stamp = text.substr(0, space);
		double timestamp = 0.0;
		if (path.empty()) {
			r_issues->push_back({ p_path, line.line, "expected 'timestamp_s relative/path', got '" + line.text + "'; line skipped" });
			continue;
		}
		if (!parse_number(stamp, &timestamp)) {
			r_issues->push_back({ p_path, line.line, "'" + std::string(stamp) + "' is not a finite timestamp in seconds; line skipped" });
			continue;
		}
		const std::string outside = path_leaves_recording(std::string(path));
		if (!outside.empty()) {
			r_issues->push_back({ p_path, line.line, outside + "; frame skipped" });
			continue;
		}
		if (!r_frames->empty() && !(timestamp > r_frames->back().timestamp_s)) {
			const bool repeats = timestamp == r_frames->back().timestamp_s;
			r_issues->push_back({ p_path, line.line,
					"timestamp " + format_number(timestamp) + (repeats ? " repeats line " : " goes backwards (before line ") +
							std::to_string(r_frames->back().line) + (repeats ? "'s" : "'s " + format_number(r_frames->back().timestamp_s) + ")") +
							"; timestamps must increase; frame " + std::string(path) + " skipped" });
			continue;
		}
		r_frames->push_back(FrameRef{ timestamp, std::string(path), line.line });
	}
	return std::string();
}

std::string check_png_bytes(const std::vector<uint8_t> &p_bytes) {
	PngInfo info;
	const std::string error = parse_png_header(p_bytes.data(), p_bytes.size(), &info);
	if (!error.empty()) {
		return error;
	}
	return walk_png_chunks(p_bytes.size(), [&](uint64_t p_offset, uint8_t *r_header) {
		std::memcpy(r_header, p_bytes.data() + p_offset, 8);
		return true;
	});
}

namespace {

// An open file's size, with the stream back at its start; -1 when it cannot be told.
std::streamoff stream_size(std::ifstream &p_file) {
	p_file.seekg(0, std::ios::end);
	const std::streamoff size = p_file.tellg();
	p_file.seekg(0);
	return size;
}

// read_png_info on an open file of p_size bytes whose first bytes (up to PNG_HEADER_SIZE) are read.
std::string png_info_of(std::ifstream &p_file, std::streamoff p_size, const uint8_t *p_header, const std::string &p_path, PngInfo *r_info) {
	std::string error = parse_png_header(p_header, size_t(std::min<std::streamoff>(p_size, PNG_HEADER_SIZE)), r_info);
	if (!error.empty()) {
		return p_path + ": " + error;
	}
	// The common case: the file ends with IEND. Otherwise walk the chunks, which tells data after
	// IEND (allowed) from a file cut short.
	uint8_t tail[12] = {};
	if (p_size >= std::streamoff(PNG_HEADER_SIZE + 12)) {
		p_file.clear();
		p_file.seekg(p_size - 12);
		p_file.read(reinterpret_cast<char *>(tail), 12);
		if (p_file && std::memcmp(tail, PNG_IEND, 12) == 0) {
			return std::string();
		}
	}
	p_file.clear();
	error = walk_png_chunks(uint64_t(p_size), [&](uint64_t p_offset, uint8_t *r_header) {
		p_file.clear();
		p_file.seekg(std::streamoff(p_offset));
		p_file.read(reinterpret_cast<char *>(r_header), 8);
		return bool(p_file);
	});
	return error.empty() ? error : p_path + ": " + error;
}

// Opens a frame file to read its header: "" or what is wrong, naming the file; r_size: its length.
std::string open_for_header(const std::string &p_path, std::ifstream *r_file, std::streamoff *r_size) {
	if (!file_exists(p_path)) {
		return not_a_file_error(p_path);
	}
	r_file->open(p_path, std::ios::binary);
	if (!*r_file) {
		return p_path + ": cannot be opened for reading";
	}
	*r_size = stream_size(*r_file);
	return *r_size < 0 ? p_path + ": cannot be read" : "";
}

} // namespace

std::string read_png_info(const std::string &p_path, PngInfo *r_info) {
	std::ifstream file;
	std::streamoff size = 0;
	const std::string error = open_for_header(p_path, &file, &size);
	if (!error.empty()) {
		return error;
	}
	uint8_t header[PNG_HEADER_SIZE] = {};
	file.read(reinterpret_cast<char *>(header), std::streamsize(std::min<std::streamoff>(size, PNG_HEADER_SIZE)));
	return png_info_of(file, size, header, p_path, r_info);
}

std::string read_frame_file_info(const std::string &p_path, FrameFileInfo *r_info) {
	std::ifstream file;
	std::streamoff size = 0;
	const std::string open_error = open_for_header(p_path, &file, &size);
	if (!open_error.empty()) {
		return open_error;
	}
	constexpr size_t HEADER_BYTES = std::max(PNG_HEADER_SIZE, kRawFrameHeaderBytes);
	uint8_t header[HEADER_BYTES] = {};
	const size_t have = size_t(std::min<std::streamoff>(size, HEADER_BYTES));
	file.read(reinterpret_cast<char *>(header), std::streamsize(have));
	FrameFileInfo info;
	if (have >= 8 && std::memcmp(header, PNG_SIGNATURE, 8) == 0) {
		info.kind = FrameFileKind::Png;
		const std::string error = png_info_of(file, size, header, p_path, &info.png);
		if (!error.empty()) {
			return error;
		}
		info.width = info.png.width;
		info.height = info.png.height;
		*r_info = info;
		return std::string();
	}
	if (!zstd_magic(header, have)) {
		return p_path + ": neither a PNG nor a RoomProbe raw frame" + (size == 0 ? std::string(" (empty file)") : std::string());
	}
	info.kind = FrameFileKind::RawFrame;
	const std::string error = raw_frame_parse_header(header, have, &info.raw);
	if (!error.empty()) {
		return p_path + ": " + error;
	}
	const uint64_t needed = kRawFrameHeaderBytes + info.raw.data_bytes;
	if (uint64_t(size) < needed) {
		return p_path + ": truncated: the raw frame ends at byte " + std::to_string(size) + "; its header says " + std::to_string(needed) + " bytes";
	}
	if (uint64_t(size) > needed) {
		return p_path + ": corrupt raw frame: " + std::to_string(uint64_t(size) - needed) + " bytes after its zstd data (the header says " +
				std::to_string(needed) + " bytes in all)";
	}
	info.width = info.raw.width;
	info.height = info.raw.height;
	*r_info = info;
	return std::string();
}

std::string decode_frame_file(const std::string &p_path, cv::Mat *r_image, FrameFileKind *r_kind) {
	std::vector<uint8_t> bytes;
	const std::string unreadable = read_whole_file(p_path, &bytes);
	if (!unreadable.empty()) {
		return unreadable;
	}
	const bool png = bytes.size() >= 8 && std::memcmp(bytes.data(), PNG_SIGNATURE, 8) == 0;
	if (png) {
		const std::string error = check_png_bytes(bytes);
		if (!error.empty()) {
			return p_path + ": " + error;
		}
	} else if (!zstd_magic(bytes.data(), bytes.size())) {
		return p_path + ": neither a PNG nor a RoomProbe raw frame" + (bytes.empty() ? std::string(" (empty file)") : std::string());
	}
	return catch_all(p_path, [&]() -> std::string {
		cv::Mat image;
		const std::string problem = png ? png_decode(bytes.data(), bytes.size(), &image) : raw_frame_decode(bytes.data(), bytes.size(), &image);
		if (!problem.empty()) {
			return p_path + ": " + problem;
		}
		*r_image = image;
		if (r_kind != nullptr) {
			*r_kind = png ? FrameFileKind::Png : FrameFileKind::RawFrame;
		}
		return std::string();
	});
}

namespace {

// EOI may be followed by a little padding; a cut-short file has none within this many last bytes.
constexpr size_t JPEG_TAIL_BYTES = 64;

// The header checks of read_jpeg_info on bytes in memory (a whole file): "" or the problem.
std::string parse_jpeg(const std::vector<uint8_t> &p_bytes, JpegInfo *r_info) {
	const size_t size = p_bytes.size();
	if (size < 2 || p_bytes[0] != 0xff || p_bytes[1] != 0xd8) {
		return "not a JPEG file (no start-of-image marker)";
	}
	bool found_end = false;
	for (size_t i = size >= JPEG_TAIL_BYTES ? size - JPEG_TAIL_BYTES : 0; i + 1 < size; i++) {
		found_end = found_end || (p_bytes[i] == 0xff && p_bytes[i + 1] == 0xd9);
	}
	size_t at = 2;
	while (true) {
		// Markers: 0xff (any fill 0xff), then the code; all but the standalone ones have a length.
		if (at >= size || p_bytes[at] != 0xff) {
			return at >= size ? "truncated: the JPEG ends at byte " + std::to_string(size) + ", before its frame header"
							  : "corrupt JPEG: no marker at byte " + std::to_string(at);
		}
		while (at < size && p_bytes[at] == 0xff) {
			at++;
		}
		if (at >= size) {
			return "truncated: the JPEG ends at byte " + std::to_string(size) + ", inside a marker";
		}
		const uint8_t code = p_bytes[at++];
		if (code == 0x01 || (code >= 0xd0 && code <= 0xd7)) {
			continue;
		}
		if (code == 0xd9 || code == 0xda) {
			return "corrupt JPEG: no frame header (SOF) before its image data";
		}
		if (at + 2 > size) {
			return "truncated: the JPEG ends at byte " + std::to_string(size) + ", inside a segment";
		}
		const size_t length = (size_t(p_bytes[at]) << 8) | p_bytes[at + 1];
		if (length < 2 || at + length > size) {
			return "truncated: the JPEG ends at byte " + std::to_string(size) + ", inside a segment that needs " + std::to_string(at + length) + " bytes";
		}
		const bool frame_header = code >= 0xc0 && code <= 0xcf && code != 0xc4 && code != 0xc8 && code != 0xcc;
		if (frame_header) {
			if (length < 8) {
				return "corrupt JPEG: a frame header of " + std::to_string(length) + " bytes";
			}
			JpegInfo info;
			info.height = (int(p_bytes[at + 3]) << 8) | p_bytes[at + 4];
			info.width = (int(p_bytes[at + 5]) << 8) | p_bytes[at + 6];
			info.components = p_bytes[at + 7];
			if (info.width == 0 || info.height == 0) {
				return "corrupt JPEG: zero width or height in its frame header";
			}
			if (!found_end) {
				return "truncated: the JPEG has no end-of-image marker (EOI) in its last " + std::to_string(JPEG_TAIL_BYTES) + " bytes";
			}
			*r_info = info;
			return std::string();
		}
		at += length;
	}
}

} // namespace

bool is_jpeg_path(const std::string &p_path) {
	std::string extension = fs::path(p_path).extension().string();
	std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	return extension == ".jpg" || extension == ".jpeg";
}

std::string read_jpeg_info(const std::string &p_path, JpegInfo *r_info) {
	// Datasets' JPEGs are tens of kilobytes: reading the whole file is simpler than seeking.
	std::vector<uint8_t> bytes;
	const std::string error = read_whole_file(p_path, &bytes);
	if (!error.empty()) {
		return error;
	}
	const std::string problem = parse_jpeg(bytes, r_info);
	return problem.empty() ? problem : p_path + ": " + problem;
}

std::string decode_jpeg(const std::string &p_path, cv::Mat *r_image) {
	std::vector<uint8_t> bytes;
	const std::string error = read_whole_file(p_path, &bytes);
	if (!error.empty()) {
		return error;
	}
	JpegInfo info;
	const std::string problem = parse_jpeg(bytes, &info);
	if (!problem.empty()) {
		return p_path + ": " + problem;
	}
	return catch_all(p_path, [&]() -> std::string {
		cv::Mat image;
		const std::string problem = jpeg_decode(bytes.data(), bytes.size(), &image);
		if (!problem.empty()) {
			return p_path + ": " + problem;
		}
		*r_image = image;
		return std::string();
	});
}

std::string write_png(const std::string &p_path, const cv::Mat &p_image) {
	return png_write(p_path, p_image);
}

std::string write_exr_rgb(const std::string &p_path, const cv::Mat &p_rgb, bool p_full_float) {
	if (p_rgb.empty() || p_rgb.type() != CV_32FC3) {
		return p_path + ": an HDR image must be CV_32FC3 (linear R, G, B); got " + (p_rgb.empty() ? std::string("an empty image") : describe_type(p_rgb.type()));
	}
	const cv::Mat rgb = p_rgb.isContinuous() ? p_rgb : p_rgb.clone();
	const float *values = rgb.ptr<float>();
	const size_t count = rgb.total() * 3;
	const float limit = p_full_float ? std::numeric_limits<float>::max() : 65504.0f; // half's largest finite value
	for (size_t i = 0; i < count; i++) {
		if (!std::isfinite(values[i]) || std::abs(values[i]) > limit) {
			const size_t pixel = i / 3;
			return p_path + ": value " + format_number(values[i]) + " at pixel (" + std::to_string(pixel % rgb.cols) + ", " +
					std::to_string(pixel / rgb.cols) + ") is " + (std::isfinite(values[i]) ? "beyond half's range (65504); write full float" : "not finite");
		}
	}
	return catch_all(p_path, [&]() -> std::string {
		Imf::Header header(rgb.cols, rgb.rows);
		header.compression() = Imf::ZIP_COMPRESSION;
		const Imf::PixelType stored = p_full_float ? Imf::FLOAT : Imf::HALF;
		const char *names[3] = { "R", "G", "B" };
		for (const char *name : names) {
			header.channels().insert(name, Imf::Channel(stored));
		}
		// OpenEXR converts pixel types when reading, not when writing: the buffer is in the stored type.
		Imf::FrameBuffer buffer;
		std::vector<half> halves;
		char *base = const_cast<char *>(reinterpret_cast<const char *>(values));
		size_t element = sizeof(float);
		if (!p_full_float) {
			halves.assign(values, values + count);
			base = reinterpret_cast<char *>(halves.data());
			element = sizeof(half);
		}
		const size_t x_stride = 3 * element;
		const size_t y_stride = x_stride * size_t(rgb.cols);
		for (int c = 0; c < 3; c++) {
			buffer.insert(names[c], Imf::Slice(stored, base + c * element, x_stride, y_stride));
		}
		return write_exr(p_path, header, buffer, rgb.rows);
	});
}

std::string read_exr_size(const std::string &p_path, int *r_width, int *r_height) {
	if (!file_exists(p_path)) {
		return not_a_file_error(p_path);
	}
	return catch_all(p_path, [&]() -> std::string {
		Imf::InputFile file(p_path.c_str());
		const Imath::Box2i window = file.header().dataWindow();
		const int64_t width = int64_t(window.max.x) - window.min.x + 1;
		const int64_t height = int64_t(window.max.y) - window.min.y + 1;
		if (width <= 0 || height <= 0 || width > kImageMaxSidePx || height > kImageMaxSidePx) {
			return p_path + ": the data window is " + std::to_string(width) + " x " + std::to_string(height) + " pixels, not 1 to " +
					std::to_string(kImageMaxSidePx) + " a side";
		}
		*r_width = int(width);
		*r_height = int(height);
		return std::string();
	});
}

std::string read_exr_rgb(const std::string &p_path, cv::Mat *r_rgb) {
	if (!file_exists(p_path)) {
		return not_a_file_error(p_path);
	}
	return catch_all(p_path, [&]() -> std::string {
		Imf::InputFile file(p_path.c_str());
		const Imf::ChannelList &channels = file.header().channels();
		const char *names[3] = { "R", "G", "B" };
		for (const char *name : names) {
			if (channels.findChannel(name) == nullptr) {
				std::string present;
				for (Imf::ChannelList::ConstIterator it = channels.begin(); it != channels.end(); ++it) {
					present += (present.empty() ? "" : ", ") + std::string(it.name());
				}
				return p_path + ": no '" + name + "' channel (an HDR image needs R, G and B; it has " + (present.empty() ? "none" : present) + ")";
			}
		}
		const Imath::Box2i window = file.header().dataWindow();
		// In 64 bits: a damaged header's window can span more than an int.
		const int64_t width = int64_t(window.max.x) - window.min.x + 1;
		const int64_t height = int64_t(window.max.y) - window.min.y + 1;
		if (width <= 0 || height <= 0) {
			return p_path + ": empty data window";
		}
		if (width > kImageMaxSidePx || height > kImageMaxSidePx || width * height > EXR_MAX_PIXELS) {
			return p_path + ": the image claims " + std::to_string(width) + " x " + std::to_string(height) + " pixels, above the limit of " +
					std::to_string(kImageMaxSidePx) + " a side and " + std::to_string(EXR_MAX_PIXELS) + " in all";
		}
		cv::Mat rgb(int(height), int(width), CV_32FC3);
		Imf::FrameBuffer buffer;
		for (int c = 0; c < 3; c++) {
			buffer.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb.ptr<float>() + c, window, 3 * sizeof(float), 3 * sizeof(float) * size_t(width)));
		}
		file.setFrameBuffer(buffer);
		file.readPixels(window.min.y, window.max.y);
		*r_rgb = rgb;
		return std::string();
	});
}

// An error "<path>:<line>: problem" from load_tum_trajectory, as an issue.
RecordingIssue issue_from_error(const std::string &p_path, const std::string &p_error, const std::string &p_suffix) {
	RecordingIssue issue{ p_path, 0, p_error };
	if (p_error.rfind(p_path + ":", 0) == 0) {
		std::string rest = p_error.substr(p_path.size() + 1);
		size_t digits = 0;
		while (digits < rest.size() && std::isdigit(static_cast<unsigned char>(rest[digits]))) {
			digits++;
		}
		if (digits > 0 && digits < rest.size() && rest[digits] == ':') {
			parse_int(rest.substr(0, digits), &issue.line);
			rest = rest.substr(digits + 1);
		}
		while (!rest.empty() && rest.front() == ' ') {
			rest.erase(rest.begin());
		}
		issue.message = rest;
	}
	issue.message += p_suffix;
	return issue;
}

void associate(const std::vector<double> &p_a, const std::vector<double> &p_b, double p_max_difference_s,
		std::vector<std::pair<size_t, size_t>> *r_pairs) {
	r_pairs->clear();
	std::vector<std::tuple<double, size_t, size_t>> candidates;
	size_t first_b = 0;
	for (size_t i = 0; i < p_a.size(); i++) {
		while (first_b < p_b.size() && !(p_b[first_b] > p_a[i] - p_max_difference_s)) {
			first_b++;
		}
		for (size_t j = first_b; j < p_b.size() && p_b[j] < p_a[i] + p_max_difference_s; j++) {
			const double difference = std::abs(p_a[i] - p_b[j]);
			if (difference < p_max_difference_s) {
				candidates.emplace_back(difference, i, j);
			}
		}
	}
	std::sort(candidates.begin(), candidates.end());
	std::vector<bool> used_a(p_a.size(), false);
	std::vector<bool> used_b(p_b.size(), false);
	for (const auto &[difference, i, j] : candidates) {
		if (!used_a[i] && !used_b[j]) {
			used_a[i] = true;
			used_b[j] = true;
			r_pairs->emplace_back(i, j);
		}
	}
	std::sort(r_pairs->begin(), r_pairs->end());
}

} // namespace recording_io

} // namespace roomprobe
