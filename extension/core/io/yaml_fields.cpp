#include "yaml_fields.h"

#include "image_codec.h"
#include "input_path.h"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string_view>
#include <vector>

namespace roomprobe {

// The parse error carries "(<line>): <what>" in the exception's func field and the parser's
// function in err.
std::string describe_yaml_parse_error(const cv::Exception &p_exception) {
	if (p_exception.code != cv::Error::StsParseError) {
		return p_exception.err;
	}
	const std::string &detail = p_exception.func;
	const size_t close = detail.find("): ");
	if (detail.rfind("(", 0) == 0 && close != std::string::npos) {
		return "line " + detail.substr(1, close - 1) + ": " + detail.substr(close + 3);
	}
	return detail;
}

namespace {

bool is_control(unsigned char p_c) { return (p_c < 0x20 && p_c != '\t') || p_c == 0x7f; }
bool is_key_char(char p_c) { return std::isalnum(static_cast<unsigned char>(p_c)) != 0 || p_c == '_'; }
// A plain scalar's characters: numbers (1e-3, .nan, -.inf), words (pinhole_radtan), dates.
bool is_scalar_char(char p_c) { return is_key_char(p_c) || p_c == '.' || p_c == '+' || p_c == '-' || p_c == '/'; }

std::string screen_values(std::string_view p_text, int *r_depth);

// The inside of a one-line flow map, "key: value, key: value" (photometric.yaml's list items),
// each value a scalar, a quoted string or a list closed within it. "" or what is wrong.
std::string screen_flow_map(std::string_view p_inside) {
	size_t start = 0;
	while (start <= p_inside.size()) {
		size_t end = start;
		int depth = 0; // a comma inside a list separates the list's items, not the pairs
		for (; end < p_inside.size() && (p_inside[end] != ',' || depth > 0); end++) {
			if (p_inside[end] == '[') {
				depth++;
			} else if (p_inside[end] == ']' && depth > 0) {
				depth--;
			}
		}
		std::string_view pair = p_inside.substr(start, end - start);
		pair.remove_prefix(std::min(pair.size(), pair.find_first_not_of(' ')));
		size_t key = 0;
		while (key < pair.size() && is_key_char(pair[key])) {
			key++;
		}
		if (key == 0 || key + 1 >= pair.size() || pair[key] != ':' || pair[key + 1] != ' ') {
			return "a '{ }' map holds 'key: value' pairs, got '" + std::string(pair) + "'";
		}
		const std::string_view value = pair.substr(key + 2);
		int value_depth = 0;
		const std::string problem = value.find_first_of("{}") != std::string_view::npos ? std::string("a map inside a '{ }' map") : screen_values(value, &value_depth);
		if (!problem.empty() || value_depth != 0) {
			return problem.empty() ? std::string("a list in a '{ }' map must close inside it") : problem;
		}
		start = end + 1;
	}
	return std::string();
}

// The flow part of a line: scalars, quoted strings, '[', ']', ',', a one-line '{ key: value }'
// map and a trailing comment; r_depth carries the open '[' count across lines. "" or what is wrong.
std::string screen_values(std::string_view p_text, int *r_depth) {
	constexpr int MAX_DEPTH = 8; // RoomProbe's files nest lists two deep
	for (size_t i = 0; i < p_text.size(); i++) {
		const char c = p_text[i];
		if (c == '[') {
			if (++*r_depth > MAX_DEPTH) {
				return "lists nested more than " + std::to_string(MAX_DEPTH) + " deep";
			}
		} else if (c == ']') {
			if (--*r_depth < 0) {
				return "']' without its '['";
			}
		} else if (c == '{') {
			const size_t close = p_text.find('}', i + 1);
			if (close == std::string_view::npos) {
				return std::string("a '{' map that does not close on its line");
			}
			const std::string problem = screen_flow_map(p_text.substr(i + 1, close - i - 1));
			if (!problem.empty()) {
				return problem;
			}
			i = close;
		} else if (c == '"' || c == '\'') {
			const size_t close = p_text.find(c, i + 1);
			if (close == std::string_view::npos) {
				return std::string("a quoted string that does not end on its line");
			}
			i = close;
		} else if (c == '#' && (i == 0 || p_text[i - 1] == ' ')) {
			return std::string(); // a comment to the end of the line
		} else if (is_scalar_char(c) && (i == 0 || !is_scalar_char(p_text[i - 1]))) {
			// A plain scalar: a whole number must fit 32 bits, or OpenCV reads another number
			// (3000000000 reads as -1294967296) without a word.
			size_t end = i;
			while (end < p_text.size() && is_scalar_char(p_text[end])) {
				end++;
			}
			const std::string_view token = p_text.substr(i, end - i);
			const size_t sign = token.find_first_not_of("+-") == std::string_view::npos ? 0 : token.find_first_not_of("+-");
			const std::string_view magnitude = token.substr(sign);
			// OpenCV reads whole numbers with strtol(.., 0): a leading 0 means octal, 0x hex.
			const bool hexadecimal = magnitude.size() > 1 && magnitude[0] == '0' && (magnitude[1] == 'x' || magnitude[1] == 'X');
			const bool octal = magnitude.size() > 1 && magnitude[0] == '0' && std::isdigit(static_cast<unsigned char>(magnitude[1])) != 0 &&
					magnitude.find_first_of(".eE") == std::string_view::npos; // 0.5 and 01e5 are read as reals
			if (sign <= 1 && (hexadecimal || octal)) {
				return "the number " + std::string(token) + " starts with 0 (OpenCV would read it as octal or hexadecimal)";
			}
			if (sign <= 1 && !magnitude.empty() && magnitude.find_first_not_of("0123456789") == std::string_view::npos) {
				const char *limit = sign == 1 && token[0] == '-' ? "2147483648" : "2147483647";
				if (magnitude.size() > 10 || (magnitude.size() == 10 && magnitude > limit)) {
					return "the whole number " + std::string(token) + " does not fit 32 bits (OpenCV would read another number)";
				}
			}
			i = end - 1;
		} else if (!is_scalar_char(c) && c != ',' && c != ' ') {
			char text[64];
			std::snprintf(text, sizeof(text), "unexpected character '%c' (0x%02x)", std::isprint(static_cast<unsigned char>(c)) ? c : '?',
					static_cast<unsigned char>(c));
			return text;
		}
	}
	return std::string();
}

// Whether p_text is well-formed UTF-8 (comments may hold any language, not stray bytes).
bool is_utf8(std::string_view p_text) {
	for (size_t i = 0; i < p_text.size();) {
		const unsigned char c = static_cast<unsigned char>(p_text[i]);
		const size_t length = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
		if (length == 0 || i + length > p_text.size()) {
			return false;
		}
		for (size_t k = 1; k < length; k++) {
			if ((static_cast<unsigned char>(p_text[i + k]) >> 6) != 0x2) {
				return false;
			}
		}
		i += length;
	}
	return true;
}

// The block structure: every line that starts a map field or a list item lines up with a block
// that is open, and a block opens only under "key:" or "-" with nothing after it. OpenCV's parser
// loops for ever on some misaligned texts (a map entry indented under nothing, then a list item
// at column 0), so misalignment is refused here, naming the line.
class BlockLayout {
public:
	enum class Kind { Map, List };

	// "" or what is wrong with a line at p_indent of p_kind; p_opens: nothing follows ':' or '-'.
	std::string add(size_t p_indent, Kind p_kind, bool p_opens) {
		const char *what = p_kind == Kind::Map ? "field" : "list item";
		if (opening) {
			opening = false;
			if (p_indent > parent_indent) {
				levels.push_back({ p_indent, p_kind });
				return finish(p_indent, p_opens);
			}
			if (p_indent == parent_indent && p_kind == Kind::List) { // YAML allows it; cv::FileStorage does not
				return "a list item must be indented under its key";
			}
			// "key:" with nothing under it is YAML's null: the line belongs to an outer block.
		}
		if (levels.empty()) {
			if (p_indent != 0) {
				return std::string("the first ") + what + " is indented (the document starts at column 0)";
			}
			levels.push_back({ 0, p_kind });
			return finish(p_indent, p_opens);
		}
		while (!levels.empty() && levels.back().indent > p_indent) {
			levels.pop_back();
		}
		if (levels.empty() || levels.back().indent != p_indent) {
			return std::string("this ") + what + "'s indentation (" + std::to_string(p_indent) + " spaces) lines up with no block above it";
		}
		if (levels.back().kind != p_kind) {
			return std::string("a ") + what + " among " + (p_kind == Kind::Map ? "list items" : "fields") + " at the same indentation";
		}
		return finish(p_indent, p_opens);
	}

private:
	struct Level {
		size_t indent;
		Kind kind;
	};
	std::string finish(size_t p_indent, bool p_opens) {
		opening = p_opens;
		parent_indent = p_indent;
		return std::string();
	}
	std::vector<Level> levels;
	bool opening = false;
	size_t parent_indent = 0;
};

bool is_yaml_header(std::string_view p_line) {
	// "%YAML:1.0" (what cv::FileStorage writes) or "%YAML 1.x".
	return p_line.size() == 9 && p_line.rfind("%YAML", 0) == 0 && (p_line[5] == ':' || p_line[5] == ' ') && p_line[6] == '1' &&
			p_line[7] == '.' && std::isdigit(static_cast<unsigned char>(p_line[8])) != 0;
}

} // namespace

std::string screen_yaml_text(const std::string &p_text) {
	int depth = 0; // '[' still open
	int number = 0;
	BlockLayout layout;
	for (size_t start = 0; start < p_text.size();) {
		number++;
		const size_t end = std::min(p_text.find('\n', start), p_text.size());
		std::string_view line(p_text.data() + start, end - start);
		start = end + 1;
		auto fail = [&](const std::string &p_what) { return "line " + std::to_string(number) + ": " + p_what; };
		while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) {
			line.remove_suffix(1);
		}
		const size_t indent = std::min(line.find_first_not_of(' '), line.size());
		std::string_view rest = line.substr(indent);
		if (number == 1 && rest.rfind("%YAML", 0) == 0) {
			if (!is_yaml_header(line)) {
				return fail("the header must be '%YAML:1.0'");
			}
			continue;
		}
		if (rest.empty()) {
			continue;
		}
		if (rest.front() == '#') { // a whole-line comment: any text in UTF-8, no control characters
			if (std::any_of(rest.begin(), rest.end(), [](char c) { return is_control(static_cast<unsigned char>(c)); })) {
				return fail("a control character in a comment");
			}
			if (!is_utf8(rest)) {
				return fail("a comment that is not UTF-8 text");
			}
			continue;
		}
		for (const char c : rest) {
			if (is_control(static_cast<unsigned char>(c)) || static_cast<unsigned char>(c) >= 0x80) {
				return fail(c == '\t' ? "a tab (YAML indents with spaces)" : "a byte that is not printable ASCII outside a comment");
			}
		}
		if (depth == 0) {
			if (rest.rfind("---", 0) == 0) {
				if (indent != 0 || rest.size() != 3) {
					return fail("text after the document marker '---' (a line of its own in YAML files here)");
				}
				continue;
			}
			BlockLayout::Kind kind = BlockLayout::Kind::Map;
			if (rest == "-" || rest.rfind("- ", 0) == 0) { // a list item: its value follows
				kind = BlockLayout::Kind::List;
				rest.remove_prefix(std::min<size_t>(2, rest.size()));
			} else { // key: [value]
				size_t key = 0;
				while (key < rest.size() && is_key_char(rest[key])) {
					key++;
				}
				if (key == 0 || std::isdigit(static_cast<unsigned char>(rest[0])) != 0) {
					return fail("expected 'key: value', a list item '- ' or a comment");
				}
				if (key == rest.size() || rest[key] != ':') {
					return fail("expected ':' after the key '" + std::string(rest.substr(0, key)) + "'");
				}
				rest.remove_prefix(key + 1);
				if (!rest.empty() && rest.front() != ' ') {
					return fail("expected a space after ':'");
				}
			}
			const size_t value = std::min(rest.find_first_not_of(' '), rest.size());
			const std::string misaligned = layout.add(indent, kind, value == rest.size() || rest[value] == '#');
			if (!misaligned.empty()) {
				return fail(misaligned);
			}
		}
		const std::string problem = screen_values(rest, &depth);
		if (!problem.empty()) {
			return fail(problem);
		}
	}
	if (depth != 0) {
		return "line " + std::to_string(number) + ": a list '[' is never closed";
	}
	return std::string();
}

bool YamlFieldReader::fail(const std::string &p_field, const std::string &p_problem) {
	error = p_field + ": " + p_problem;
	return false;
}

bool YamlFieldReader::check_keys(const cv::FileNode &p_map, const std::string &p_prefix,
		std::initializer_list<const char *> p_allowed, std::initializer_list<const char *> p_required) {
	std::set<std::string> seen;
	for (cv::FileNodeIterator it = p_map.begin(); it != p_map.end(); ++it) {
		const std::string key = (*it).name();
		bool known = false;
		for (const char *allowed : p_allowed) {
			known = known || key == allowed;
		}
		if (!known) {
			return fail(p_prefix + key, "unknown field");
		}
		if (!seen.insert(key).second) {
			return fail(p_prefix + key, "given twice");
		}
	}
	for (const char *key : p_required) {
		if (!seen.count(key)) {
			return fail(p_prefix + key, "missing");
		}
	}
	return true;
}

bool YamlFieldReader::present(const cv::FileNode &p_node, const std::string &p_field) {
	if (p_node.empty() || p_node.isNone()) {
		return fail(p_field, "missing");
	}
	return true;
}

template <typename T>
bool YamlFieldReader::typed(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key,
		bool (cv::FileNode::*p_is)() const, const char *p_problem, T *r_value) {
	const cv::FileNode node = p_parent[p_key];
	if (!present(node, p_prefix + p_key)) {
		return false;
	}
	if (!(node.*p_is)()) {
		return fail(p_prefix + p_key, p_problem);
	}
	*r_value = static_cast<T>(node);
	return true;
}

bool YamlFieldReader::map(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, cv::FileNode *r_map) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isMap, "must be a map of fields", r_map);
}

bool YamlFieldReader::integer(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, int *r_value) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isInt, "must be an integer", r_value);
}

bool YamlFieldReader::text(const cv::FileNode &p_parent, const std::string &p_prefix, const char *p_key, std::string *r_value) {
	return typed(p_parent, p_prefix, p_key, &cv::FileNode::isString, "must be a string", r_value);
}

bool YamlFieldReader::number(const cv::FileNode &p_node, const std::string &p_field, double *r_value) {
	if (!present(p_node, p_field)) {
		return false;
	}
	if (!p_node.isInt() && !p_node.isReal()) {
		return fail(p_field, "must be a number");
	}
	const double value = static_cast<double>(p_node);
	if (non_finite == NonFinite::Refuse && !std::isfinite(value)) {
		// std::to_chars writes "inf", "-inf", "nan" or "-nan", whatever the format asked for.
		char buffer[16];
		const std::to_chars_result written = std::to_chars(buffer, buffer + sizeof(buffer), value);
		return fail(p_field, "must be finite (got " + std::string(buffer, written.ptr) + ")");
	}
	if (std::isfinite(value) && std::abs(value) > YAML_MAX_MAGNITUDE) {
		return fail(p_field, "must be within +-1e9 (got " + std::to_string(value) +
						"): cv::FileStorage writes whole numbers beyond 32 bits as integers that read back as other numbers");
	}
	*r_value = value;
	return true;
}

bool YamlFieldReader::numbers(const cv::FileNode &p_node, const std::string &p_field, size_t p_count, double *r_values) {
	if (!present(p_node, p_field)) {
		return false;
	}
	if (!p_node.isSeq() || p_node.size() != p_count) {
		return fail(p_field, "must be a list of " + std::to_string(p_count) + " numbers");
	}
	for (size_t i = 0; i < p_count; i++) {
		if (!number(p_node[static_cast<int>(i)], p_field + "[" + std::to_string(i) + "]", &r_values[i])) {
			return false;
		}
	}
	return true;
}

std::string check_yaml_text(const std::string &p_text) {
	if (p_text.rfind("%YAML", 0) != 0) {
		return "malformed YAML: the first line must be '%YAML:1.0' (cv::FileStorage's header)";
	}
	const std::string unsafe = screen_yaml_text(p_text);
	return unsafe.empty() ? unsafe : "malformed YAML: " + unsafe;
}

std::string open_yaml_file(const std::string &p_path, cv::FileStorage *r_storage) {
	std::error_code ec;
	const std::string not_a_file = input_file_problem(p_path);
	if (!not_a_file.empty()) {
		return not_a_file;
	}
	const uintmax_t size = std::filesystem::file_size(p_path, ec);
	if (ec || size > YAML_MAX_FILE_BYTES) {
		return p_path + (ec ? ": cannot be read" : ": " + std::to_string(size) + " bytes, more than a YAML file RoomProbe reads (16 MiB)");
	}
	std::vector<uint8_t> bytes;
	const std::string unreadable = read_file_bytes(p_path, &bytes);
	if (!unreadable.empty()) {
		return unreadable;
	}
	const std::string text(bytes.begin(), bytes.end());
	const std::string malformed = check_yaml_text(text);
	if (!malformed.empty()) {
		return p_path + ": " + malformed;
	}
	try {
		if (!r_storage->open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML)) {
			return p_path + ": malformed YAML";
		}
	} catch (const cv::Exception &e) {
		return p_path + ": " + describe_yaml_parse_error(e);
	}
	return "";
}

} // namespace roomprobe
