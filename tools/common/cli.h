#pragma once
// The command-line tools' argument walking (tools/<name>/*_main.cpp): one argument at a time,
// with the value that follows an option checked where it is read.

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
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
	// The value as an integer > 0 (false otherwise).
	bool positive_integer(long *r_value) {
		std::string v;
		if (!value(&v)) {
			return false;
		}
		char *end = nullptr;
		const long n = std::strtol(v.c_str(), &end, 10);
		if (end == v.c_str() || *end != '\0' || n <= 0) {
			return false;
		}
		*r_value = n;
		return true;
	}
	// The value as a number > 0 (false otherwise).
	bool positive_number(double *r_value) {
		std::string v;
		if (!value(&v)) {
			return false;
		}
		char *end = nullptr;
		const double x = std::strtod(v.c_str(), &end);
		if (end == v.c_str() || *end != '\0' || !(x > 0.0)) {
			return false;
		}
		*r_value = x;
		return true;
	}

	// The value as a number >= 0 (false otherwise).
	bool non_negative_number(double *r_value) {
		std::string v;
		if (!value(&v)) {
			return false;
		}
		char *end = nullptr;
		const double x = std::strtod(v.c_str(), &end);
		if (end == v.c_str() || *end != '\0' || !(x >= 0.0) || !std::isfinite(x)) {
			return false;
		}
		*r_value = x;
		return true;
	}
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

} // namespace roomprobe::cli
