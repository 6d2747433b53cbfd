// io/zip_limits (issue #38: a zipped recording's zip bomb inflated without limit into user://): a
// zip's table of contents is read without inflating anything, and an archive whose declared sizes
// exceed the limits is refused, naming the zip and the entry or the total. The archives here are
// made by hand, so that their declared sizes can be anything (a petabyte, 1000-fold); the Godot
// test test_nodes_rig_capture.gd unpacks real ones (ZIPPacker's) and a real zip bomb.
#include "io/zip_limits.h"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

void put16(std::vector<uint8_t> &r_bytes, uint32_t p_value) {
	r_bytes.push_back(uint8_t(p_value));
	r_bytes.push_back(uint8_t(p_value >> 8));
}
void put32(std::vector<uint8_t> &r_bytes, uint32_t p_value) {
	put16(r_bytes, p_value & 0xFFFF);
	put16(r_bytes, p_value >> 16);
}
void put64(std::vector<uint8_t> &r_bytes, uint64_t p_value) {
	put32(r_bytes, uint32_t(p_value));
	put32(r_bytes, uint32_t(p_value >> 32));
}

struct Entry {
	std::string name;
	uint64_t compressed, uncompressed; // as declared: nothing is inflated to check them
};

// A zip archive whose entries declare p_entries' sizes: a local header and p_data bytes each (the
// data is never read), then the central directory and its end record; with p_zip64, every size
// and the directory's place in zip64 records, as zip tools write archives past 4 GiB.
std::vector<uint8_t> make_zip(const std::vector<Entry> &p_entries, bool p_zip64 = false, const std::string &p_comment = "") {
	std::vector<uint8_t> zip;
	std::vector<uint32_t> offsets;
	for (const Entry &e : p_entries) {
		offsets.push_back(uint32_t(zip.size()));
		put32(zip, 0x04034b50);
		for (int i = 0; i < 22; i++) {
			zip.push_back(0); // version, flags, method, time, date, crc, sizes: unread
		}
		put16(zip, uint32_t(e.name.size()));
		put16(zip, 0);
		zip.insert(zip.end(), e.name.begin(), e.name.end());
		zip.insert(zip.end(), 16, 0xAB); // some data
	}
	const uint64_t directory_at = zip.size();
	for (size_t i = 0; i < p_entries.size(); i++) {
		const Entry &e = p_entries[i];
		put32(zip, 0x02014b50);
		put16(zip, 45);
		put16(zip, 45);
		put16(zip, 0);
		put16(zip, 8); // deflate
		put32(zip, 0);
		put32(zip, 0); // crc
		put32(zip, p_zip64 ? 0xFFFFFFFF : uint32_t(e.compressed));
		put32(zip, p_zip64 ? 0xFFFFFFFF : uint32_t(e.uncompressed));
		put16(zip, uint32_t(e.name.size()));
		put16(zip, p_zip64 ? 20 : 0);
		put16(zip, 0);
		put16(zip, 0);
		put16(zip, 0);
		put32(zip, 0);
		put32(zip, offsets[i]);
		zip.insert(zip.end(), e.name.begin(), e.name.end());
		if (p_zip64) {
			put16(zip, 1);
			put16(zip, 16);
			put64(zip, e.uncompressed);
			put64(zip, e.compressed);
		}
	}
	const uint64_t directory_bytes = zip.size() - directory_at;
	if (p_zip64) {
		const uint64_t record_at = zip.size();
		put32(zip, 0x06064b50);
		put64(zip, 44);
		put16(zip, 45);
		put16(zip, 45);
		put32(zip, 0);
		put32(zip, 0);
		put64(zip, p_entries.size());
		put64(zip, p_entries.size());
		put64(zip, directory_bytes);
		put64(zip, directory_at);
		put32(zip, 0x07064b50);
		put32(zip, 0);
		put64(zip, record_at);
		put32(zip, 1);
	}
	put32(zip, 0x06054b50);
	put16(zip, 0);
	put16(zip, 0);
	put16(zip, p_zip64 ? 0xFFFF : uint32_t(p_entries.size()));
	put16(zip, p_zip64 ? 0xFFFF : uint32_t(p_entries.size()));
	put32(zip, p_zip64 ? 0xFFFFFFFF : uint32_t(directory_bytes));
	put32(zip, p_zip64 ? 0xFFFFFFFF : uint32_t(directory_at));
	put16(zip, uint32_t(p_comment.size()));
	zip.insert(zip.end(), p_comment.begin(), p_comment.end());
	return zip;
}

std::string list(const std::vector<uint8_t> &p_zip, std::vector<ZipEntryInfo> *r_entries) {
	const ZipReadAt read = [&](uint64_t p_offset, size_t p_size, uint8_t *p_buffer) -> size_t {
		if (p_offset >= p_zip.size()) {
			return 0;
		}
		const size_t n = std::min<size_t>(p_size, p_zip.size() - size_t(p_offset));
		std::memcpy(p_buffer, p_zip.data() + p_offset, n);
		return n;
	};
	return list_zip_entries("rec.zip", p_zip.size(), read, r_entries);
}

// What a recording's files look like zipped: small indexes that compress well, frames that do not.
std::vector<Entry> a_recording() {
	return { { "living/", 0, 0 }, { "living/rig.yaml", 900, 3000 }, { "living/rgb.txt", 40000, 300000 }, { "living/rgb/000000.zst", 400000, 410000 },
		{ "living/groundtruth/cubemap_000000.exr", 2000000, 2100000 } };
}

constexpr uint64_t PLENTY = uint64_t(1) << 40; // free bytes

} // namespace

TEST_CASE("zip limits: a recording's archive is listed with its declared sizes and passes, zip64 too") {
	for (bool zip64 : { false, true }) {
		CAPTURE(zip64);
		std::vector<ZipEntryInfo> entries;
		REQUIRE(list(make_zip(a_recording(), zip64, zip64 ? "" : "a comment"), &entries) == "");
		REQUIRE(entries.size() == 5);
		CHECK(entries[2].name == "living/rgb.txt");
		CHECK(entries[2].compressed_bytes == 40000);
		CHECK(entries[2].uncompressed_bytes == 300000);
		CHECK(check_zip_limits("rec.zip", entries, ZipLimits(), PLENTY) == "");
	}
	// Sizes past 4 GiB are read from the zip64 fields, not taken as 0xFFFFFFFF.
	std::vector<ZipEntryInfo> entries;
	REQUIRE(list(make_zip({ { "living/huge.bin", uint64_t(5) << 30, uint64_t(6) << 30 } }, true), &entries) == "");
	CHECK(entries[0].uncompressed_bytes == uint64_t(6) << 30);
	CHECK(entries[0].compressed_bytes == uint64_t(5) << 30);
}

TEST_CASE("zip limits: a zip bomb is refused before anything is inflated, naming the zip and the entry or the total") {
	std::vector<ZipEntryInfo> entries;
	// One entry 1000-fold (deflate on zeros): refused by its ratio.
	REQUIRE(list(make_zip({ { "living/rig.yaml", 900, 3000 }, { "living/rgb/000000.zst", 65536, 64 << 20 } }), &entries) == "");
	std::string error = check_zip_limits("rec.zip", entries, ZipLimits(), PLENTY);
	CHECK(contains(error, "rec.zip: entry 'living/rgb/000000.zst' inflates 1024-fold (65536 bytes to 64.0 MiB), more than the 100-fold"));
	CHECK(contains(error, "nothing unpacked"));
	// Small files may compress well: an index of 1 MiB at 500-fold passes.
	REQUIRE(list(make_zip({ { "living/rgb.txt", 2000, 1 << 20 } }), &entries) == "");
	CHECK(check_zip_limits("rec.zip", entries, ZipLimits(), PLENTY) == "");
	// Many entries each within the ratio, a petabyte in all: refused by the total.
	std::vector<Entry> many;
	for (int i = 0; i < 600; i++) {
		many.push_back({ "living/rgb/" + std::to_string(i) + ".zst", uint64_t(1) << 30, (uint64_t(1) << 31) - 1 });
	}
	REQUIRE(list(make_zip(many, true), &entries) == "");
	error = check_zip_limits("rec.zip", entries, ZipLimits(), PLENTY);
	CHECK(contains(error, "rec.zip: unpacks to 1200.0 GiB, more than a zipped recording may (32.0 GiB); nothing unpacked"));
	// One entry past what Godot's ZIPReader reads whole (2 GiB), whatever its ratio.
	REQUIRE(list(make_zip({ { "living/big.exr", uint64_t(3) << 30, uint64_t(3) << 30 } }, true), &entries) == "");
	CHECK(contains(check_zip_limits("rec.zip", entries, ZipLimits(), PLENTY), "entry 'living/big.exr' unpacks to 3.0 GiB, more than one file"));
	// More than the disk has free.
	REQUIRE(list(make_zip(a_recording()), &entries) == "");
	CHECK(contains(check_zip_limits("rec.zip", entries, ZipLimits(), 1000000), "rec.zip: unpacks to 2.7 MiB, and only 1000000 bytes is free"));
	// The limits are the caller's.
	ZipLimits tight;
	tight.max_entries = 3;
	CHECK(contains(check_zip_limits("rec.zip", entries, tight, PLENTY), "rec.zip: 5 entries, more than a zipped recording may hold (3)"));
}

TEST_CASE("zip limits: what is not a zip, or a damaged one, is named, never read past its end") {
	std::vector<ZipEntryInfo> entries;
	const std::string text = "not a zip at all, just some text that is long enough to search";
	CHECK(contains(list(std::vector<uint8_t>(text.begin(), text.end()), &entries), "rec.zip: not a zip archive"));
	CHECK(contains(list({}, &entries), "rec.zip: not a zip archive"));
	// The end record claims more entries than its table of contents holds.
	std::vector<uint8_t> zip = make_zip(a_recording());
	zip[zip.size() - 22 + 10] = 200;
	zip[zip.size() - 22 + 8] = 200;
	CHECK(contains(list(zip, &entries), "rec.zip: damaged"));
	// A name length running past the table's end.
	std::vector<uint8_t> cut = make_zip({ { "living/rig.yaml", 900, 3000 } });
	const size_t entry_at = cut.size() - 22 - (46 + 15);
	cut[entry_at + 28] = 0xFF; // name length 255 + ...
	CHECK(contains(list(cut, &entries), "rec.zip: damaged: entry 1 of its table of contents runs past its end"));
	// zip64 markers without the zip64 records.
	zip = make_zip(a_recording());
	for (size_t i = zip.size() - 22 + 12; i < zip.size() - 22 + 20; i++) {
		zip[i] = 0xFF;
	}
	CHECK(contains(list(zip, &entries), "rec.zip: damaged: its zip64 end record is missing"));
	// A split archive.
	zip = make_zip(a_recording());
	zip[zip.size() - 22 + 4] = 1;
	CHECK(contains(list(zip, &entries), "split"));
}
