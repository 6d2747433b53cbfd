// The command-line tools' argument walker (tools/common/cli.h cli::Arguments and its number
// parsers, which every roomprobe_* tool reads its options with). The input is an argv: arguments
// separated by NUL bytes, walked as a tool walks them, with options of each kind the tools take.
// No read past the last argument; a value taken is finite and within its option's range, a list
// has exactly the count asked for; a number parsed, printed with 17 digits and parsed again is the
// same number.
#include "fuzz_common.h"

#include "../../tools/common/cli.h"

#include <algorithm>
#include <cstring>
#include <vector>

using namespace roomprobe;

namespace {

void same_when_parsed_again(double p_value) {
	char text[64];
	std::snprintf(text, sizeof(text), "%.17g", p_value);
	double again = 0.0;
	fuzz::require(cli::parse_number(text, &again) && again == p_value, "a number printed and parsed again is the same:", text);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	std::vector<std::string> words(1, "roomprobe_fuzz");
	std::string word;
	for (size_t i = 0; i < p_size; i++) {
		if (p_data[i] == 0) {
			words.push_back(word);
			word.clear();
		} else {
			word += char(p_data[i]);
		}
	}
	words.push_back(word);
	std::vector<char *> argv;
	for (std::string &w : words) {
		argv.push_back(w.data());
	}
	argv.push_back(nullptr);

	cli::Arguments args(int(words.size()), argv.data(), 1);
	std::string arg;
	while (args.next(&arg)) {
		if (arg == "--threads") {
			long n = 0;
			if (args.integer_in(1, cli::MAX_THREADS, &n)) {
				fuzz::require(n >= 1 && n <= cli::MAX_THREADS, "an integer option is within its range");
			}
		} else if (arg == "--square-m") {
			double x = 0.0;
			if (args.number_in(0.001, 1.0, &x)) {
				fuzz::require(x >= 0.001 && x <= 1.0, "a number option is within its range");
				same_when_parsed_again(x);
			}
		} else if (arg == "--seconds") {
			double x = 0.0;
			if (args.positive_number(1e6, &x)) {
				fuzz::require(x > 0.0 && x <= 1e6, "a positive option is within (0, max]");
			}
		} else if (arg == "--offset") {
			double x = 0.0;
			if (args.non_negative_number(&x)) {
				fuzz::require(std::isfinite(x) && x >= 0.0, "a non-negative option is finite and >= 0");
				same_when_parsed_again(x);
			}
		} else if (arg == "--gains") {
			double gains[3] = { -1.0, -1.0, -1.0 };
			if (args.number_list(3, gains)) {
				for (double g : gains) {
					fuzz::require(std::isfinite(g), "a list's numbers are finite");
					same_when_parsed_again(g);
				}
			}
		} else if (arg == "--stops") {
			std::string text;
			std::vector<double> stops;
			if (args.value(&text) && cli::parse_number_list(text, &stops)) {
				fuzz::require(!stops.empty(), "a list that parses has a number");
				fuzz::require(size_t(std::count(text.begin(), text.end(), ',')) + 1 == stops.size(), "a list has one number per comma-separated item");
			}
		} else {
			long n = 0;
			if (cli::parse_integer(arg, &n)) {
				double x = 0.0;
				fuzz::require(cli::parse_number(std::to_string(n), &x) && x == double(n), "a whole number is a number");
			}
		}
	}
	return 0;
}
