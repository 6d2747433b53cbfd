// The fuzz suite's short form (issue #39): a fuzz target's LLVMFuzzerTestOneInput run once on
// every file of the folders given (its corpus and the inputs that once failed), built with the
// normal compiler against the normal core. No libFuzzer and no sanitizers: a crash, a broken
// invariant (abort) or a hang of the loaders on an input the fuzzer kept is what it finds; the
// long form (./roomprobe fuzz TARGET --seconds S) searches for new ones.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size);
// Called first when a target has it, as libFuzzer does (the recording target's seed mode).
extern "C" int LLVMFuzzerInitialize(int *p_argc, char ***p_argv) __attribute__((weak));

int main(int argc, char **argv) {
	if (LLVMFuzzerInitialize != nullptr) {
		LLVMFuzzerInitialize(&argc, &argv);
	}
	std::vector<std::filesystem::path> inputs;
	for (int i = 1; i < argc; i++) {
		std::error_code ec;
		if (std::filesystem::is_directory(argv[i], ec)) {
			for (const auto &entry : std::filesystem::recursive_directory_iterator(argv[i], ec)) {
				if (entry.is_regular_file(ec)) {
					inputs.push_back(entry.path());
				}
			}
		} else if (std::filesystem::is_regular_file(argv[i], ec)) {
			inputs.push_back(argv[i]);
		} else {
			std::fprintf(stderr, "replay: %s is neither a file nor a folder\n", argv[i]);
			return 2;
		}
	}
	std::sort(inputs.begin(), inputs.end()); // the same order on every machine
	for (const std::filesystem::path &path : inputs) {
		std::ifstream file(path, std::ios::binary);
		const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
		if (!file.good() && !file.eof()) {
			std::fprintf(stderr, "replay: %s cannot be read\n", path.c_str());
			return 2;
		}
		std::fprintf(stderr, "replay: %s\n", path.c_str()); // the last one named is the one that failed
		LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
	}
	std::printf("replayed %zu inputs\n", inputs.size());
	return 0;
}
