#pragma once
// A zip archive's table of contents, read without inflating anything, and the limits a zipped
// recording is unpacked within (issue #38: a zip bomb inflated without limit into user://). The
// Godot nodes unpack a recording given as a .zip (godot/convert/project_paths.h); before a byte is
// inflated, every entry's declared sizes are checked here, and the unpacker then takes no more
// than an entry declares.
//
// Every function returns "" or what is wrong, naming the archive, and never throws.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace roomprobe {

struct ZipEntryInfo {
	std::string name; // as stored ("living/rgb/000000.zst"; a folder ends with '/')
	uint64_t compressed_bytes = 0;
	uint64_t uncompressed_bytes = 0;
};

// Reads p_size bytes at p_offset of the archive into p_buffer; returns how many it read.
using ZipReadAt = std::function<size_t(uint64_t p_offset, size_t p_size, uint8_t *p_buffer)>;

// The entries of the archive p_name (for messages) of p_archive_bytes bytes, from its central
// directory (zip64 too). "" with r_entries filled, or "NAME: not a zip archive ..." / "NAME:
// damaged: ...".
std::string list_zip_entries(const std::string &p_name, uint64_t p_archive_bytes, const ZipReadAt &p_read, std::vector<ZipEntryInfo> *r_entries);

struct ZipLimits {
	// The most an archive may unpack to in all: a long recording, not a disk's worth.
	uint64_t max_total_bytes = uint64_t(32) << 30;
	// The most one entry may hold: Godot's ZIPReader reads an entry whole into one array (2 GiB).
	uint64_t max_entry_bytes = (uint64_t(1) << 31) - 1;
	// The most an entry larger than ratio_exempt_bytes may grow when inflated. A recording's large
	// files are already compressed (zstd or PNG frames, ZIP-compressed EXRs), about 1:1 in a zip;
	// deflate reaches 1032:1 on zeros, which is how a zip bomb inflates.
	double max_ratio = 100.0;
	uint64_t ratio_exempt_bytes = uint64_t(1) << 20; // small files (indexes, YAML) may compress well
	size_t max_entries = 1000000;
};

// "" when the entries of p_name keep within p_limits and fit in p_free_bytes (the unpacking disk's
// free space), else "NAME: ..." naming the entry or the total and the limit. Nothing is unpacked
// from an archive refused here.
std::string check_zip_limits(const std::string &p_name, const std::vector<ZipEntryInfo> &p_entries, const ZipLimits &p_limits, uint64_t p_free_bytes);

} // namespace roomprobe
