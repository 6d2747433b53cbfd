#pragma once
// Typed fields out of YAML that cv::FileStorage has parsed (the rig file, a recording's room.yaml):
// integers, numbers, lists of numbers, strings and maps, and the check that a map holds exactly the
// keys its schema allows. Every error names the field's full path, as "field: problem", e.g.
// "fisheye.xi: missing", "rgb.width: must be an integer", "floorplan_m[2][0]: must be a number";
// the caller puts the file's name in front.
//
// p_prefix is the path of the map a field is in, with its dot ("fisheye.", or "" at the top);
// p_field is a field's whole path. Each method returns false after the first problem, which is
// then in error.

#include "opencv.h"

#include <cstddef>
#include <initializer_list>
#include <string>

namespace roomprobe {

// What cv::FileStorage's YAML parser may be given: "" when p_text keeps to the YAML that
// RoomProbe's files use, else "line N: what". Fuzzing found malformed texts on which OpenCV 4.10's
// parser never returns ("---J a: 1", stray '%' or control bytes inside a block), so the text is
// screened first, line by line: the '%YAML:1.0' header; comments in UTF-8; "---" alone;
// "key: value", "key:" and "- value" with space indentation, each lining up with an open block
// (a misaligned field or list item hung the parser too); values of plain scalars, quoted strings
// and '[' ']' lists (across lines); printable ASCII outside comments. Files written by
// cv::FileStorage and the hand-written ones in calib/ pass.
std::string screen_yaml_text(const std::string &p_text);

// The largest magnitude a number in RoomProbe's YAML may have. OpenCV 4.10 writes a whole
// double of 2^31 or more without a decimal point (525071067811865.0 as "525071067811865"), and
// its parser then reads a 32-bit integer (-1569026023): found by fuzzing the rig file. No
// camera parameter, distance or time RoomProbe stores comes near 1e9, so larger values are
// refused at loading (and so never saved), and the screen refuses whole numbers beyond 32 bits.
inline constexpr double YAML_MAX_MAGNITUDE = 1e9;
// The checks a YAML file's text gets before cv::FileStorage parses it: the '%YAML' header that
// FileStorage needs to tell YAML from XML and JSON, then screen_yaml_text. "" or "malformed YAML: why".
std::string check_yaml_text(const std::string &p_text);

// The largest YAML file RoomProbe reads: its own files are a few kilobytes.
inline constexpr size_t YAML_MAX_FILE_BYTES = size_t(16) << 20;
// The one way RoomProbe opens a YAML file that a user may give (synth.yaml, a board file,
// photometric.yaml, ...): read whole (a regular file of at most YAML_MAX_FILE_BYTES), screened by
// check_yaml_text, then parsed from memory. "" with r_storage open, or "PATH: what is wrong".
std::string open_yaml_file(const std::string &p_path, cv::FileStorage *r_storage);

// cv::FileStorage's parse error (text parsed from memory) as "line <line>: <what>"; other OpenCV
// errors as OpenCV words them.
std::string describe_yaml_parse_error(const cv::Exception &p_exception);

class YamlFieldReader {
public:
	// Whether a number may be NaN or infinite (YAML's .nan, .inf). Accept leaves the value's range
	// to the caller's own checks; Refuse fails it as "must be finite (got inf)".
	enum class NonFinite {
		Accept,
		Refuse,
	};

	std::string error; // "field: problem"; the first problem met

	explicit YamlFieldReader(NonFinite p_non_finite) :
			non_finite(p_non_finite) {}

	// Sets error to "p_field: p_problem"; returns false.
	bool fail(const std::string &p_field, const std::string &p_problem);

	// Every key of p_map is one of p_allowed, once ("unknown field", "given twice"); each of
	// p_required is there ("missing"). A misspelt key is an error, not a default.
	bool check_keys(const cv::FileNode &p_map, const std::string &p_prefix, std::initializer_list<const char *> p_allowed,
			std::initializer_list<const char *> p_required);
	// The keys of p_map are exactly p_keys, each once.
	bool check_keys(const cv::FileNode &p_map, const std::string &p_prefix, std::initializer_list<const char *> p_keys) {
		return check_keys(p_map, p_prefix, p_keys, p_keys);
	}

	// p_parent[p_key], which must be a map.
	bool map(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, cv::FileNode *r_map);
	bool integer(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, int *r_value);
	bool text(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, std::string *r_value);

	// A number, integer or real, named p_field in messages.
	bool number(const cv::FileNode &p_node, const std::string &p_field, double *r_value);
	// A list of exactly p_count numbers; an element's path is p_field[i].
	bool numbers(const cv::FileNode &p_node, const std::string &p_field, size_t p_count, double *r_values);

	// number() and numbers() of p_parent[p_key], named p_prefix + p_key.
	bool real(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, double *r_value) {
		return number(p_parent[p_key], p_prefix + p_key, r_value);
	}
	bool reals(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, size_t p_count, double *r_values) {
		return numbers(p_parent[p_key], p_prefix + p_key, p_count, r_values);
	}

private:
	NonFinite non_finite;

	// p_node is there (not absent, not YAML's null); otherwise fails with "missing".
	bool present(const cv::FileNode &p_node, const std::string &p_field);
	// p_parent[p_key] as a T, when (node.*p_is)() says it holds one; otherwise fails with p_problem.
	template <typename T>
	bool typed(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, bool (cv::FileNode::*p_is)() const,
			const char *p_problem, T *r_value);
};

} // namespace roomprobe
