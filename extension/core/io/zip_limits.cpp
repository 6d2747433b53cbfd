#include "zip_limits.h"

#include <algorithm>
#include <cstdio>

namespace roomprobe {

namespace {

// The zip format's records (APPNOTE.TXT): their signatures and fixed sizes.
constexpr uint32_t EOCD_SIGNATURE = 0x06054b50; // end of central directory
constexpr uint32_t ZIP64_LOCATOR_SIGNATURE = 0x07064b50;
constexpr uint32_t ZIP64_EOCD_SIGNATURE = 0x06064b50;
constexpr uint32_t ENTRY_SIGNATURE = 0x02014b50; // a central directory header
constexpr size_t EOCD_BYTES = 22, ZIP64_LOCATOR_BYTES = 20, ZIP64_EOCD_BYTES = 56, ENTRY_BYTES = 46;
constexpr size_t MAX_COMMENT_BYTES = 65535;
// A central directory of a million entries with long names is some 100 MB; beyond this it is not
// a recording's.
constexpr uint64_t MAX_DIRECTORY_BYTES = uint64_t(512) << 20;

uint16_t u16(const uint8_t *p) {
	return uint16_t(p[0] | (p[1] << 8));
}
uint32_t u32(const uint8_t *p) {
	return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}
uint64_t u64(const uint8_t *p) {
	return uint64_t(u32(p)) | (uint64_t(u32(p + 4)) << 32);
}

std::string size_text(uint64_t p_bytes) {
	char text[48];
	if (p_bytes >= (uint64_t(1) << 30)) {
		std::snprintf(text, sizeof(text), "%.1f GiB", double(p_bytes) / double(uint64_t(1) << 30));
	} else if (p_bytes >= (uint64_t(1) << 20)) {
		std::snprintf(text, sizeof(text), "%.1f MiB", double(p_bytes) / double(uint64_t(1) << 20));
	} else {
		std::snprintf(text, sizeof(text), "%llu bytes", (unsigned long long)p_bytes);
	}
	return text;
}

bool read_exactly(const ZipReadAt &p_read, uint64_t p_offset, size_t p_size, uint8_t *p_buffer) {
	return p_read(p_offset, p_size, p_buffer) == p_size;
}

} // namespace

std::string list_zip_entries(const std::string &p_name, uint64_t p_archive_bytes, const ZipReadAt &p_read, std::vector<ZipEntryInfo> *r_entries) {
	r_entries->clear();
	const std::string not_zip = p_name + ": not a zip archive (no end of central directory record)";
	if (p_archive_bytes < EOCD_BYTES) {
		return not_zip;
	}
	// The end record is the last thing in the archive but its comment: searched from the end.
	const size_t tail = size_t(std::min<uint64_t>(p_archive_bytes, EOCD_BYTES + MAX_COMMENT_BYTES));
	std::vector<uint8_t> end(tail);
	const uint64_t tail_at = p_archive_bytes - tail;
	if (!read_exactly(p_read, tail_at, tail, end.data())) {
		return p_name + ": cannot be read";
	}
	size_t eocd = std::string::npos;
	for (size_t i = tail - EOCD_BYTES + 1; i-- > 0;) {
		if (u32(&end[i]) == EOCD_SIGNATURE && i + EOCD_BYTES + u16(&end[i + 20]) <= tail) {
			eocd = i;
			break;
		}
	}
	if (eocd == std::string::npos) {
		return not_zip;
	}
	const uint8_t *e = &end[eocd];
	uint64_t count = u16(e + 10), directory_bytes = u32(e + 12), directory_at = u32(e + 16);
	uint64_t directory_end = tail_at + eocd; // the central directory ends where the end record (or the zip64 one) begins
	if (u16(e + 4) != 0 || u16(e + 6) != 0 || u16(e + 8) != u16(e + 10)) {
		return p_name + ": a split (multi-part) zip archive; give it as one file";
	}
	if (count == 0xFFFF || directory_bytes == 0xFFFFFFFF || directory_at == 0xFFFFFFFF) { // zip64
		uint8_t locator[ZIP64_LOCATOR_BYTES], record[ZIP64_EOCD_BYTES];
		const uint64_t locator_at = tail_at + eocd;
		if (locator_at < ZIP64_LOCATOR_BYTES || !read_exactly(p_read, locator_at - ZIP64_LOCATOR_BYTES, ZIP64_LOCATOR_BYTES, locator) ||
				u32(locator) != ZIP64_LOCATOR_SIGNATURE) {
			return p_name + ": damaged: its zip64 end record is missing";
		}
		const uint64_t record_at = u64(locator + 8);
		if (record_at > p_archive_bytes - ZIP64_EOCD_BYTES || !read_exactly(p_read, record_at, ZIP64_EOCD_BYTES, record) ||
				u32(record) != ZIP64_EOCD_SIGNATURE) {
			return p_name + ": damaged: its zip64 end record is missing";
		}
		count = u64(record + 32);
		directory_bytes = u64(record + 40);
		directory_at = u64(record + 48);
		directory_end = record_at;
	}
	if (directory_bytes > MAX_DIRECTORY_BYTES) {
		return p_name + ": its table of contents is " + size_text(directory_bytes) + ", more than a recording's (" + size_text(MAX_DIRECTORY_BYTES) + ")";
	}
	if (directory_bytes > directory_end || count > directory_bytes / ENTRY_BYTES) {
		return p_name + ": damaged: its table of contents does not fit in the archive";
	}
	// Data before the archive (a self-extracting stub) shifts every offset alike: the directory is
	// read where it ends, just before the end record.
	(void)directory_at;
	std::vector<uint8_t> directory(static_cast<size_t>(directory_bytes));
	if (!read_exactly(p_read, directory_end - directory_bytes, directory.size(), directory.data())) {
		return p_name + ": cannot be read";
	}
	r_entries->reserve(size_t(count));
	size_t at = 0;
	for (uint64_t i = 0; i < count; i++) {
		const std::string damaged = p_name + ": damaged: entry " + std::to_string(i + 1) + " of its table of contents ";
		if (at + ENTRY_BYTES > directory.size() || u32(&directory[at]) != ENTRY_SIGNATURE) {
			return damaged + "is not where it should be";
		}
		const uint8_t *h = &directory[at];
		const size_t name_bytes = u16(h + 28), extra_bytes = u16(h + 30), comment_bytes = u16(h + 32);
		if (at + ENTRY_BYTES + name_bytes + extra_bytes + comment_bytes > directory.size()) {
			return damaged + "runs past its end";
		}
		ZipEntryInfo entry;
		entry.name.assign(reinterpret_cast<const char *>(h + ENTRY_BYTES), name_bytes);
		entry.compressed_bytes = u32(h + 20);
		entry.uncompressed_bytes = u32(h + 24);
		// Sizes of 0xFFFFFFFF are in the zip64 extra field (id 1): the uncompressed size first,
		// then the compressed one, each only when its 32-bit field says so.
		const bool big_uncompressed = entry.uncompressed_bytes == 0xFFFFFFFF, big_compressed = entry.compressed_bytes == 0xFFFFFFFF;
		if (big_uncompressed || big_compressed) {
			const uint8_t *extra = h + ENTRY_BYTES + name_bytes, *extra_end = extra + extra_bytes;
			bool found = false;
			while (extra + 4 <= extra_end) {
				const uint16_t id = u16(extra), bytes = u16(extra + 2);
				if (extra + 4 + bytes > extra_end) {
					break;
				}
				if (id == 1) {
					const uint8_t *field = extra + 4, *field_end = field + bytes;
					if (big_uncompressed && field + 8 <= field_end) {
						entry.uncompressed_bytes = u64(field);
						field += 8;
					}
					if (big_compressed && field + 8 <= field_end) {
						entry.compressed_bytes = u64(field);
					}
					found = true;
					break;
				}
				extra += 4 + bytes;
			}
			if (!found) {
				return damaged + "('" + entry.name + "') has no zip64 sizes";
			}
		}
		r_entries->push_back(std::move(entry));
		at += ENTRY_BYTES + name_bytes + extra_bytes + comment_bytes;
	}
	return "";
}

std::string check_zip_limits(const std::string &p_name, const std::vector<ZipEntryInfo> &p_entries, const ZipLimits &p_limits, uint64_t p_free_bytes) {
	if (p_entries.size() > p_limits.max_entries) {
		return p_name + ": " + std::to_string(p_entries.size()) + " entries, more than a zipped recording may hold (" + std::to_string(p_limits.max_entries) +
				"); nothing unpacked";
	}
	uint64_t total = 0;
	for (const ZipEntryInfo &entry : p_entries) {
		if (entry.uncompressed_bytes > p_limits.max_entry_bytes) {
			return p_name + ": entry '" + entry.name + "' unpacks to " + size_text(entry.uncompressed_bytes) + ", more than one file of a zipped recording may ("
					+ size_text(p_limits.max_entry_bytes) + "); nothing unpacked";
		}
		if (entry.uncompressed_bytes > p_limits.ratio_exempt_bytes &&
				double(entry.uncompressed_bytes) > p_limits.max_ratio * double(std::max<uint64_t>(entry.compressed_bytes, 1))) {
			char ratio[32];
			std::snprintf(ratio, sizeof(ratio), "%.0f", double(entry.uncompressed_bytes) / double(std::max<uint64_t>(entry.compressed_bytes, 1)));
			char limit[32];
			std::snprintf(limit, sizeof(limit), "%.0f", p_limits.max_ratio);
			return p_name + ": entry '" + entry.name + "' inflates " + ratio + "-fold (" + size_text(entry.compressed_bytes) + " to " +
					size_text(entry.uncompressed_bytes) + "), more than the " + limit +
					"-fold a recording's files do (a zip bomb, or not a recording); nothing unpacked";
		}
		total += entry.uncompressed_bytes; // each within max_entry_bytes, so no wrap
	}
	if (total > p_limits.max_total_bytes) {
		return p_name + ": unpacks to " + size_text(total) + ", more than a zipped recording may (" + size_text(p_limits.max_total_bytes) + "); nothing unpacked";
	}
	if (total > p_free_bytes) {
		return p_name + ": unpacks to " + size_text(total) + ", and only " + size_text(p_free_bytes) + " is free where it is unpacked; nothing unpacked";
	}
	return "";
}

} // namespace roomprobe
