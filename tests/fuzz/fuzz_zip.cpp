// A zipped recording's table of contents (io/zip_limits.h), read before anything is inflated, as
// RigCapture does with a .zip: any bytes give entries or an error that names the archive, with no
// read outside the archive; the limits check then says yes or names what is over.
#include "fuzz_common.h"

#include <io/zip_limits.h>

#include <cstring>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::string name = "recording.zip";
	bool outside = false;
	const ZipReadAt read = [&](uint64_t p_offset, size_t p_bytes, uint8_t *p_buffer) -> size_t {
		if (p_offset > p_size) {
			outside = true;
			return 0;
		}
		const size_t n = size_t(std::min<uint64_t>(p_bytes, p_size - p_offset));
		if (n > 0) {
			std::memcpy(p_buffer, p_data + p_offset, n);
		}
		return n;
	};
	std::vector<ZipEntryInfo> entries;
	const std::string error = list_zip_entries(name, p_size, read, &entries);
	fuzz::require(!outside, "the table of contents is read inside the archive");
	if (!error.empty()) {
		fuzz::require(error.rfind(name, 0) == 0, "a zip error names the archive:", error);
		return 0;
	}
	const std::string over = check_zip_limits(name, entries, ZipLimits(), uint64_t(1) << 40);
	fuzz::require(over.empty() || over.rfind(name, 0) == 0, "a limit error names the archive:", over);
	ZipLimits tight;
	tight.max_total_bytes = 0;
	tight.max_entries = 0;
	const std::string tight_error = check_zip_limits(name, entries, tight, 0);
	fuzz::require(entries.empty() || !tight_error.empty(), "entries over a limit of nothing are refused");
	return 0;
}
