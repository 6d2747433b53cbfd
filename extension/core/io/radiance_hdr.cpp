#include "radiance_hdr.h"

#include "image_codec.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <exception>
#include <string_view>
#include <vector>

namespace roomprobe {

namespace {

// Radiance codes a scanline in new-style runs only when its width is in this range (a wider one
// could not say its width in the 15 bits the marker has; a narrower one gains nothing).
constexpr int kRleMinWidth = 8;
constexpr int kRleMaxWidth = 0x7fff;
// An old-style run's count is shifted 8 bits more by each run that follows one: past this, any
// count but 0 is wider than the widest scanline, and the shift stays defined.
constexpr int kOldRunMaxShift = 32;

// Bytes read front to back: every read is checked against the end first.
struct Cursor {
	const uint8_t *bytes = nullptr;
	size_t size = 0;
	size_t at = 0;
	size_t left() const { return size - at; }
};

// For messages: at most 40 characters, anything unprintable as '?' (the line may be binary).
std::string printable(std::string_view p_text) {
	std::string out(p_text.substr(0, 40));
	for (char &c : out) {
		if (c < 0x20 || c > 0x7e) {
			c = '?';
		}
	}
	return p_text.size() > 40 ? "'" + out + "...'" : "'" + out + "'";
}

// The next line, without its '\n' (nor a '\r' before it); false when the data ends first.
bool next_line(Cursor *r_cursor, std::string_view *r_line) {
	const uint8_t *start = r_cursor->bytes + r_cursor->at;
	const void *end = std::memchr(start, '\n', r_cursor->left());
	if (end == nullptr) {
		return false;
	}
	size_t length = static_cast<const uint8_t *>(end) - start;
	r_cursor->at += length + 1;
	if (length > 0 && start[length - 1] == '\r') {
		--length;
	}
	*r_line = std::string_view(reinterpret_cast<const char *>(start), length);
	return true;
}

bool starts_with_text(const Cursor &p_cursor, std::string_view p_text) {
	return p_cursor.size >= p_text.size() && std::memcmp(p_cursor.bytes, p_text.data(), p_text.size()) == 0;
}

// The magic line and the header lines, up to and with the empty line that ends them.
std::string read_header(Cursor *r_cursor) {
	if (!starts_with_text(*r_cursor, "#?RADIANCE") && !starts_with_text(*r_cursor, "#?RGBE")) {
		return "not a Radiance .hdr (it does not begin with #?RADIANCE or #?RGBE)";
	}
	std::string_view line;
	if (!next_line(r_cursor, &line)) {
		return "truncated: the data ends in its first line";
	}
	while (next_line(r_cursor, &line)) {
		if (line.empty()) {
			return "";
		}
		if (line.starts_with("FORMAT=")) {
			std::string_view format = line.substr(7);
			format.remove_prefix(std::min(format.find_first_not_of(" \t"), format.size()));
			format = format.substr(0, format.find_last_not_of(" \t") + 1);
			if (format == "32-bit_rle_xyze") {
				return "FORMAT=32-bit_rle_xyze: XYZE colour is not read, only RGBE (32-bit_rle_rgbe)";
			}
			if (format != "32-bit_rle_rgbe") {
				return "FORMAT=" + printable(format) + " is not 32-bit_rle_rgbe, the only format read";
			}
		}
		// Every other line is skipped: comments, GAMMA=, PRIMARIES=, COLORCORR= and EXPOSURE=
		// (what the pixels were multiplied by since capture). EXPOSURE is ignored on purpose:
		// cv::imread ignores it, and the panoramas keep the values they had when it read them.
	}
	return "truncated: the header has no empty line after it";
}

// Up to p_max words of p_line, split at spaces and tabs; false when it has more.
bool split_words(std::string_view p_line, size_t p_max, std::vector<std::string_view> *r_words) {
	r_words->clear();
	size_t at = 0;
	while ((at = p_line.find_first_not_of(" \t", at)) != std::string_view::npos) {
		const size_t end = std::min(p_line.find_first_of(" \t", at), p_line.size());
		if (r_words->size() == p_max) {
			return false;
		}
		r_words->push_back(p_line.substr(at, end - at));
		at = end;
	}
	return true;
}

// "-Y", "+X", ...: false for anything else.
bool is_axis(std::string_view p_word) {
	return p_word.size() == 2 && (p_word[0] == '-' || p_word[0] == '+') && (p_word[1] == 'X' || p_word[1] == 'Y');
}

bool is_count(std::string_view p_word, int64_t *r_value) {
	const char *end = p_word.data() + p_word.size();
	const std::from_chars_result parsed = std::from_chars(p_word.data(), end, *r_value);
	return parsed.ec == std::errc() && parsed.ptr == end && *r_value >= 0;
}

// "-Y HEIGHT +X WIDTH": the rows top to bottom, each left to right, the only orientation read.
std::string read_resolution(Cursor *r_cursor, int *r_width, int *r_height) {
	std::string_view line;
	if (!next_line(r_cursor, &line)) {
		return "truncated: no resolution line (-Y HEIGHT +X WIDTH) after the header";
	}
	std::vector<std::string_view> word;
	int64_t height = 0, width = 0;
	if (!split_words(line, 4, &word) || word.size() != 4 || !is_axis(word[0]) || !is_axis(word[2]) || word[0][1] == word[2][1] ||
			!is_count(word[1], &height) || !is_count(word[3], &width)) {
		return "the resolution line " + printable(line) + " is not -Y HEIGHT +X WIDTH";
	}
	if (word[0] != "-Y" || word[2] != "+X") {
		return "the resolution line " + printable(line) + " is in an orientation not read (only -Y HEIGHT +X WIDTH: top row first, left to right)";
	}
	const std::string size_problem = image_size_problem(width, height);
	if (!size_problem.empty()) {
		return "the image " + size_problem;
	}
	*r_width = static_cast<int>(width);
	*r_height = static_cast<int>(height);
	return "";
}

std::string scanline_name(int p_row, int p_height) {
	return "scanline " + std::to_string(p_row + 1) + " of " + std::to_string(p_height);
}

// A scanline in new-style runs, after its marker: the R bytes of every pixel, then G, B, E, each
// channel as runs (a count over 128: count - 128 copies of the next byte) and literals (count bytes).
std::string read_new_rle(Cursor *r_cursor, int p_width, const std::string &p_name, uint8_t *r_rgbe) {
	static const char *const CHANNEL[4] = { "R", "G", "B", "E" };
	for (int c = 0; c < 4; ++c) {
		int x = 0;
		while (x < p_width) {
			if (r_cursor->left() < 1) {
				return "truncated: the data ends inside " + p_name;
			}
			const int code = r_cursor->bytes[r_cursor->at++];
			const bool run = code > 128;
			const int count = run ? code - 128 : code;
			const auto where = [&] { return p_name + ", channel " + CHANNEL[c] + ", pixel " + std::to_string(x + 1); };
			if (count == 0) {
				return where() + ": a run of length 0";
			}
			if (count > p_width - x) {
				return where() + ": " + (run ? "a run of " + std::to_string(count) + " overflows" : std::to_string(count) + " literal bytes overflow") + " the " +
						std::to_string(p_width) + "-pixel scanline";
			}
			if (r_cursor->left() < (run ? 1u : size_t(count))) {
				return "truncated: the data ends inside " + p_name;
			}
			for (int k = 0; k < count; ++k) {
				r_rgbe[4 * (x + k) + c] = r_cursor->bytes[r_cursor->at + (run ? 0 : k)];
			}
			r_cursor->at += run ? 1 : count;
			x += count;
		}
	}
	return "";
}

// A flat scanline, 4 bytes a pixel, where (1, 1, 1, n) repeats the pixel before it n times, or
// n << 8 times right after such a run, n << 16 after two (Radiance's old-style runs). A real
// pixel never reads (1, 1, 1, e): its largest byte is 128 or more, so the two cannot be confused.
std::string read_flat(Cursor *r_cursor, int p_width, const std::string &p_name, uint8_t *r_rgbe) {
	int x = 0, shift = 0;
	while (x < p_width) {
		if (r_cursor->left() < 4) {
			return "truncated: the data ends inside " + p_name;
		}
		const uint8_t *pixel = r_cursor->bytes + r_cursor->at;
		r_cursor->at += 4;
		if (pixel[0] != 1 || pixel[1] != 1 || pixel[2] != 1) {
			std::memcpy(r_rgbe + 4 * x, pixel, 4);
			++x;
			shift = 0;
			continue;
		}
		if (x == 0) {
			return p_name + " begins with an old-style run (1, 1, 1, n), which repeats a pixel it does not have";
		}
		const uint64_t count = uint64_t(pixel[3]) << shift;
		if (count > uint64_t(p_width - x)) {
			return p_name + ", pixel " + std::to_string(x + 1) + ": an old-style run of " + std::to_string(count) + " overflows the " +
					std::to_string(p_width) + "-pixel scanline";
		}
		for (uint64_t k = 0; k < count; ++k, ++x) {
			std::memcpy(r_rgbe + 4 * x, r_rgbe + 4 * (x - 1), 4);
		}
		shift = std::min(shift + 8, kOldRunMaxShift);
	}
	return "";
}

// Each scanline says how it is coded: new-style runs begin (2, 2, width / 256, width % 256),
// which no flat pixel can (its largest byte would be below 128).
std::string read_scanline(Cursor *r_cursor, int p_width, int p_row, int p_height, uint8_t *r_rgbe) {
	const std::string name = scanline_name(p_row, p_height);
	const uint8_t *marker = r_cursor->bytes + r_cursor->at;
	const bool new_style = r_cursor->left() >= 4 && p_width >= kRleMinWidth && p_width <= kRleMaxWidth && marker[0] == 2 && marker[1] == 2 && marker[2] < 128;
	if (!new_style) {
		return read_flat(r_cursor, p_width, name, r_rgbe);
	}
	const int stated = marker[2] << 8 | marker[3];
	if (stated != p_width) {
		return name + " says it is " + std::to_string(stated) + " pixels wide, the image " + std::to_string(p_width);
	}
	r_cursor->at += 4;
	return read_new_rle(r_cursor, p_width, name, r_rgbe);
}

// r * 2^(e - 136) for e = 1..255, exact in a float (as OpenCV's ldexp(1.0, e - 136) cast to
// float, then times r: 8 significant bits at most, never below the smallest subnormal, 2^-149).
const std::array<float, 256> &exponent_scale() {
	static const std::array<float, 256> scale = [] {
		std::array<float, 256> s = {};
		for (int e = 1; e < 256; ++e) {
			s[e] = std::ldexp(1.0f, e - 136);
		}
		return s;
	}();
	return scale;
}

// Every scanline from p_cursor on; into r_rgb (R, G, B) when given, else only checked.
std::string read_pixels(Cursor p_cursor, int p_width, int p_height, cv::Mat *r_rgb) {
	std::vector<uint8_t> rgbe(size_t(p_width) * 4);
	const std::array<float, 256> &scale = exponent_scale();
	for (int y = 0; y < p_height; ++y) {
		const std::string problem = read_scanline(&p_cursor, p_width, y, p_height, rgbe.data());
		if (!problem.empty()) {
			return problem;
		}
		if (r_rgb == nullptr) {
			continue;
		}
		float *row = r_rgb->ptr<float>(y);
		for (int x = 0; x < p_width; ++x) {
			const uint8_t *q = &rgbe[4 * size_t(x)];
			const float f = scale[q[3]]; // 0 when e is 0: the pixel is black
			row[3 * x + 0] = q[0] * f;
			row[3 * x + 1] = q[1] * f;
			row[3 * x + 2] = q[2] * f;
		}
	}
	return "";
}

std::string decode(const uint8_t *p_bytes, size_t p_size, const std::string &p_name, cv::Mat *r_rgb) {
	Cursor cursor;
	cursor.bytes = p_bytes;
	cursor.size = p_bytes == nullptr ? 0 : p_size;
	int width = 0, height = 0;
	std::string problem = read_header(&cursor);
	if (problem.empty()) {
		problem = read_resolution(&cursor, &width, &height);
	}
	// Every scanline is decoded once without keeping it: a short file that claims a large image
	// is refused before the image (up to 3 GB) is allocated. It costs a pass over the runs.
	if (problem.empty()) {
		problem = read_pixels(cursor, width, height, nullptr);
	}
	if (!problem.empty()) {
		return p_name + ": " + problem;
	}
	try {
		cv::Mat rgb(height, width, CV_32FC3);
		read_pixels(cursor, width, height, &rgb);
		*r_rgb = rgb;
	} catch (const std::exception &e) { // out of memory
		return p_name + ": " + e.what();
	}
	return "";
}

} // namespace

std::string radiance_hdr_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_rgb) {
	return decode(p_bytes, p_size, "the data", r_rgb);
}

std::string radiance_hdr_read(const std::string &p_path, cv::Mat *r_rgb) {
	std::vector<uint8_t> bytes;
	const std::string error = read_file_bytes(p_path, &bytes);
	if (!error.empty()) {
		return error;
	}
	return decode(bytes.data(), bytes.size(), p_path, r_rgb);
}

} // namespace roomprobe
