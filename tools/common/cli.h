#pragma once
// The command-line tools' argument walking (tools/<name>/*_main.cpp): one argument at a time,
// with the value that follows an option checked where it is read. A number is finite and within a
// range the option's message names (issue #38); an output file is checked by one policy
// (output_file_problem).

#include <io/replace_file.h>

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <string>
#include <system_error>
#include <vector>

namespace roomprobe::cli {

// A tool's main body, guarded: an exception that reaches the program's edge (a failed allocation
// in OpenCV, a filesystem error) becomes one line naming the tool and exit code 1, never an abort.
template <typename Run>
int guarded_main(const char *p_tool, Run p_run) {
	try {
		return p_run();
	} catch (const std::exception &e) {
		std::fprintf(stderr, "%s: %s\n", p_tool, e.what());
	} catch (...) {
		std::fprintf(stderr, "%s: an unexpected error\n", p_tool);
	}
	return 1;
}

// p_text as finite numbers separated by commas ("0.3,8", "-5,0"); false on anything else.
inline bool parse_number_list(const std::string &p_text, std::vector<double> *r_values) {
	r_values->clear();
	const char *at = p_text.c_str();
	while (true) {
		char *end = nullptr;
		const double x = std::strtod(at, &end);
		if (end == at || !std::isfinite(x)) {
			return false;
		}
		r_values->push_back(x);
		if (*end == '\0') {
			return true;
		}
		if (*end != ',') {
			return false;
		}
		at = end + 1;
	}
}

// p_text as a whole number that fits a long; false on anything else ("12x", "1e3", 99999999999999999999).
inline bool parse_integer(const std::string &p_text, long *r_value) {
	char *end = nullptr;
	errno = 0;
	const long n = std::strtol(p_text.c_str(), &end, 10);
	if (end == p_text.c_str() || *end != '\0' || errno == ERANGE) {
		return false;
	}
	*r_value = n;
	return true;
}

// p_text as a finite number; false on anything else ("nan", "inf", "1e999", "0.3m").
inline bool parse_number(const std::string &p_text, double *r_value) {
	char *end = nullptr;
	const double x = std::strtod(p_text.c_str(), &end);
	if (end == p_text.c_str() || *end != '\0' || !std::isfinite(x)) {
		return false;
	}
	*r_value = x;
	return true;
}

// "[p_min, p_max]" as the messages name a range ("[0.001, 0.02]", "[1, 10000000]").
inline std::string range_text(double p_min, double p_max) {
	char text[64];
	std::snprintf(text, sizeof(text), "[%.10g, %.10g]", p_min, p_max);
	return text;
}

// The most threads a tool's pool is given: more than any machine here has cores, and each thread
// reserves a stack (roomprobe_bench --threads 100000 segfaulted).
inline constexpr long MAX_THREADS = 1024;

class Arguments {
public:
	Arguments(int p_argc, char **p_argv, int p_first) :
			argc(p_argc), argv(p_argv), index(p_first - 1) {}

	// The next argument into *r_arg; false after the last.
	bool next(std::string *r_arg) {
		if (++index >= argc) {
			return false;
		}
		*r_arg = argv[index];
		return true;
	}
	// The value after the current option; false when there is none.
	bool value(std::string *r_value) {
		if (index + 1 >= argc) {
			return false;
		}
		*r_value = argv[++index];
		return true;
	}
	// The value as a whole number in [p_min, p_max]; false otherwise (text, overflow, out of range).
	bool integer_in(long p_min, long p_max, long *r_value) {
		std::string v;
		long n = 0;
		if (!value(&v) || !parse_integer(v, &n) || n < p_min || n > p_max) {
			return false;
		}
		*r_value = n;
		return true;
	}
	// The value as a finite number in [p_min, p_max]; false otherwise (text, NaN, infinity, out of range).
	bool number_in(double p_min, double p_max, double *r_value) {
		std::string v;
		double x = 0.0;
		if (!value(&v) || !parse_number(v, &x) || !(x >= p_min && x <= p_max)) {
			return false;
		}
		*r_value = x;
		return true;
	}
	// The value as a finite number in (0, p_max]; false otherwise.
	bool positive_number(double p_max, double *r_value) {
		double x = 0.0;
		if (!number_in(0.0, p_max, &x) || !(x > 0.0)) {
			return false;
		}
		*r_value = x;
		return true;
	}
	// The value as a finite number >= 0 (false otherwise).
	bool non_negative_number(double *r_value) { return number_in(0.0, std::numeric_limits<double>::max(), r_value); }
	// The value as exactly p_count finite numbers separated by commas ("0.3,8"); false otherwise.
	bool number_list(size_t p_count, double *r_values) {
		std::string v;
		std::vector<double> values;
		if (!value(&v) || !parse_number_list(v, &values) || values.size() != p_count) {
			return false;
		}
		for (size_t i = 0; i < p_count; i++) {
			r_values[i] = values[i];
		}
		return true;
	}

private:
	int argc;
	char **argv;
	int index;
};

// True when p_path is p_input or lies inside it, both compared as canonical paths (links
// followed; p_path need not exist yet). An output there would overwrite what the tool reads.
inline bool path_within(const std::string &p_path, const std::string &p_input) {
	if (p_input.empty()) {
		return false;
	}
	std::error_code ec, path_ec;
	std::filesystem::path input = std::filesystem::weakly_canonical(p_input, ec);
	const std::filesystem::path path = std::filesystem::weakly_canonical(p_path, path_ec);
	if (ec || path_ec) {
		return false;
	}
	if (!input.has_filename()) { // "DIR/": its last part is empty
		input = input.parent_path();
	}
	auto at = path.begin();
	for (const std::filesystem::path &part : input) {
		if (at == path.end() || *at != part) {
			return false;
		}
		++at;
	}
	return true;
}

// Why p_option's output p_path cannot be written because it lies in one of p_inputs (what the tool
// reads: a recording folder, a rig file), or "". An output there could overwrite what it reads
// (bench's --save-trajectory once overwrote a recording's rgb.txt; roomprobe_room --out REC/room.yaml
// would replace the recording's own room).
inline std::string output_in_input_problem(const std::string &p_option, const std::string &p_path, const std::vector<std::string> &p_inputs) {
	for (const std::string &input : p_inputs) {
		if (path_within(p_path, input)) {
			return p_option + " " + p_path + " lies in the input " + input + ", which it would overwrite: write it elsewhere";
		}
	}
	return "";
}

// Why p_path cannot be written as p_option's file, or "": a folder, something other than a regular
// file (a device such as /dev/full), or, unless p_force, a file that exists. Every tool keeps an
// existing output unless --force.
inline std::string output_file_problem(const std::string &p_option, const std::string &p_path, bool p_force) {
	const std::string problem = check_replaceable(p_path);
	if (!problem.empty()) {
		return p_option + " " + problem;
	}
	std::error_code ec;
	if (!p_force && std::filesystem::exists(p_path, ec)) {
		return p_option + " " + p_path + " exists: it is kept (give --force to replace it)";
	}
	return "";
}

// Why files cannot be written into the folder p_folder (p_option's), or "": it is made when missing
// (its parent must exist), and a temporary file beside p_sample (a file the tool will write there) is
// made and removed, so that a folder that cannot be written is refused before any work, naming the
// system's reason ("Permission denied", "Read-only file system").
inline std::string output_folder_problem(const std::string &p_option, const std::string &p_folder, const std::string &p_sample) {
	std::error_code ec;
	std::filesystem::create_directory(p_folder, ec);
	if (ec) {
		return p_option + " " + p_folder + ": cannot create the folder (" + ec.message() + ")";
	}
	FileReplacement probe;
	const std::string problem = probe.begin((std::filesystem::path(p_folder) / p_sample).string());
	return problem.empty() ? "" : p_option + " " + p_folder + ": files cannot be written there (" + problem + ")";
}

// Why p_option's file p_path cannot be written where it is, or "": a temporary file beside it is made
// and removed (io/replace_file.h), so that a read-only folder is refused before any work, naming the
// system's reason. Nothing at p_path is touched.
inline std::string output_file_unwritable(const std::string &p_option, const std::string &p_path) {
	FileReplacement probe;
	const std::string problem = probe.begin(p_path);
	return problem.empty() ? "" : p_option + " " + problem;
}

} // namespace roomprobe::cli
