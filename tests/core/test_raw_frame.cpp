// io/raw_frame: frames as zstd-compressed samples behind a small header (docs/recording-format.md,
// "Raw frame files"): exact round trips of every sample type, a file zstd itself reads, and
// damaged or hostile files refused with their reason before anything is allocated.
#include "io/opencv.h"
#include "io/raw_frame.h"

#include "test_images.h"

#include <doctest/doctest.h>

#include <zstd.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

using namespace roomprobe;

namespace {

bool contains(const std::string &p_text, const std::string &p_part) {
	return p_text.find(p_part) != std::string::npos;
}

cv::Mat pattern(int p_type, int p_width = 53, int p_height = 37) {
	cv::Mat image(p_height, p_width, p_type);
	cv::RNG rng(11);
	if (image.depth() == CV_16F) {
		cv::Mat floats(p_height, p_width, CV_MAKETYPE(CV_32F, image.channels()));
		rng.fill(floats, cv::RNG::UNIFORM, -1000.0, 1000.0);
		floats.convertTo(image, CV_16F);
	} else if (image.depth() == CV_32F) {
		rng.fill(image, cv::RNG::UNIFORM, -1e6, 1e6);
	} else {
		rng.fill(image, cv::RNG::UNIFORM, 0, image.depth() == CV_16U ? 65536 : 256);
	}
	return image;
}

std::vector<uint8_t> encode(const cv::Mat &p_image, int p_level = kRawFrameDefaultLevel) {
	std::vector<uint8_t> bytes;
	const std::string error = raw_frame_encode(p_image, p_level, &bytes);
	REQUIRE_MESSAGE(error.empty(), error);
	return bytes;
}

std::string decode_error(const std::vector<uint8_t> &p_bytes) {
	cv::Mat image;
	const std::string error = raw_frame_decode(p_bytes.data(), p_bytes.size(), &image);
	CHECK(image.empty()); // a refused file gives no image
	return error;
}

void put_le32(std::vector<uint8_t> *r_bytes, size_t p_at, uint32_t p_value) {
	for (int i = 0; i < 4; i++) {
		(*r_bytes)[p_at + size_t(i)] = uint8_t(p_value >> (8 * i));
	}
}

} // namespace

TEST_CASE("raw frame: round trips are bit-exact: 8-bit B, G, R and gray, 16-bit depth and colour, RGBA, half and float") {
	for (const int type : { CV_8UC3, CV_16UC1, CV_8UC1, CV_16UC3, CV_8UC4, CV_16FC3, CV_32FC3, CV_32FC1 }) {
		for (const int level : { 1, 3, -1 }) {
			CAPTURE(type);
			CAPTURE(level);
			const cv::Mat image = pattern(type);
			const std::vector<uint8_t> bytes = encode(image, level);
			CHECK(raw_frame_signature(bytes.data(), bytes.size()));
			RawFrameHeader header;
			REQUIRE(raw_frame_parse_header(bytes.data(), bytes.size(), &header) == "");
			CHECK(header.width == 53);
			CHECK(header.height == 37);
			CHECK(header.cv_type() == type);
			CHECK(header.data_bytes + kRawFrameHeaderBytes == bytes.size());
			cv::Mat back;
			const std::string error = raw_frame_decode(bytes.data(), bytes.size(), &back);
			REQUIRE_MESSAGE(error.empty(), error);
			CHECK(same_samples(back, image));
		}
	}
	// Every bit of a float is kept, NaN and infinities included; a view into a larger image too.
	cv::Mat floats = pattern(CV_32FC3, 64, 48);
	floats.at<cv::Vec3f>(1, 2) = cv::Vec3f(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.0f);
	const cv::Mat view = floats(cv::Rect(1, 1, 40, 30));
	REQUIRE_FALSE(view.isContinuous());
	const std::vector<uint8_t> bytes = encode(view);
	cv::Mat back;
	REQUIRE(raw_frame_decode(bytes.data(), bytes.size(), &back) == "");
	CHECK(same_samples(back, view));
	// A frame a recording holds: 640 x 480 depth, smooth as depth is, compresses.
	cv::Mat depth(480, 640, CV_16UC1);
	for (int y = 0; y < depth.rows; y++) {
		for (int x = 0; x < depth.cols; x++) {
			depth.at<uint16_t>(y, x) = uint16_t(1000 + x + 2 * y);
		}
	}
	const std::vector<uint8_t> depth_bytes = encode(depth);
	CHECK(depth_bytes.size() < depth.total() * 2 / 2);
	REQUIRE(raw_frame_decode(depth_bytes.data(), depth_bytes.size(), &back) == "");
	CHECK(same_samples(back, depth));
}

TEST_CASE("raw frame: the file is a zstd file: zstd skips the header and gives the samples, row by row, little-endian") {
	const cv::Mat image = pattern(CV_16UC3);
	const std::vector<uint8_t> bytes = encode(image);
	// The header: a skippable frame (magic 0x184D2A5E, 24 bytes), 'RPRF', version 1, type 2 (16-bit), 3 channels, 53 x 37.
	const uint8_t expected[24] = { 0x5E, 0x2A, 0x4D, 0x18, 24, 0, 0, 0, 'R', 'P', 'R', 'F', 1, 0, 2, 3, 53, 0, 0, 0, 37, 0, 0, 0 };
	CHECK(std::memcmp(bytes.data(), expected, sizeof(expected)) == 0);
	std::vector<uint8_t> samples(image.total() * image.elemSize() + 16);
	const size_t size = ZSTD_decompress(samples.data(), samples.size(), bytes.data(), bytes.size());
	REQUIRE_FALSE(ZSTD_isError(size));
	REQUIRE(size == image.total() * image.elemSize());
	CHECK(std::memcmp(samples.data(), image.data, size) == 0);
	const uint16_t first = image.at<cv::Vec3w>(0, 0)[0];
	CHECK(samples[0] == (first & 0xFF));
	CHECK(samples[1] == (first >> 8));
}

TEST_CASE("raw frame: truncated, foreign and damaged files are refused with their reason") {
	const cv::Mat image = pattern(CV_8UC3);
	const std::vector<uint8_t> good = encode(image);

	CHECK(contains(decode_error({}), "not a RoomProbe raw frame"));
	CHECK(contains(decode_error({}), "empty file"));
	// Cut inside the header, inside the data.
	CHECK(contains(decode_error(std::vector<uint8_t>(good.begin(), good.begin() + 6)), "truncated"));
	CHECK(contains(decode_error(std::vector<uint8_t>(good.begin(), good.begin() + 20)), "inside its 32-byte header"));
	const std::string cut = decode_error(std::vector<uint8_t>(good.begin(), good.end() - 10));
	CHECK(contains(cut, "truncated: the raw frame ends at byte " + std::to_string(good.size() - 10)));
	CHECK(contains(cut, "says " + std::to_string(good.size()) + " bytes"));
	// Bytes after the data.
	std::vector<uint8_t> longer = good;
	longer.push_back(0);
	CHECK(contains(decode_error(longer), "1 bytes after its zstd data"));
	// Wrong magic: a PNG, text, a plain zstd file, another skippable frame.
	const std::vector<uint8_t> png = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R' };
	CHECK(contains(decode_error(png), "not a RoomProbe raw frame (no 'RPRF' header)"));
	const std::string text = "timestamp_s filename\n10 rgb/000000.zst\n";
	CHECK(contains(decode_error(std::vector<uint8_t>(text.begin(), text.end())), "not a RoomProbe raw frame"));
	std::vector<uint8_t> plain(ZSTD_compressBound(image.total() * 3));
	plain.resize(ZSTD_compress(plain.data(), plain.size(), image.data, image.total() * 3, 1));
	CHECK(contains(decode_error(plain), "a plain zstd file"));
	std::vector<uint8_t> other_tag = good;
	other_tag[8] = 'X';
	CHECK(contains(decode_error(other_tag), "no 'RPRF' header"));
	CHECK(zstd_magic(other_tag.data(), other_tag.size()));
	CHECK_FALSE(raw_frame_signature(other_tag.data(), other_tag.size()));
	// A later version, an unknown sample type, impossible channel counts.
	std::vector<uint8_t> version = good;
	version[12] = 2;
	CHECK(contains(decode_error(version), "version 2; this RoomProbe reads version 1"));
	std::vector<uint8_t> type = good;
	type[14] = 9;
	CHECK(contains(decode_error(type), "sample type 9"));
	for (const uint8_t channels : { 0, 5, 255 }) {
		std::vector<uint8_t> bad = good;
		bad[15] = channels;
		CHECK(contains(decode_error(bad), std::to_string(channels) + " channels (1 to 4)"));
	}
	// Data that is not what the header promised: corrupt bytes (the same length), a checksum off.
	std::vector<uint8_t> corrupt = good;
	for (size_t i = kRawFrameHeaderBytes + 20; i < corrupt.size() - 8; i += 7) {
		corrupt[i] ^= 0x5A;
	}
	const std::string corrupted = decode_error(corrupt);
	CHECK(contains(corrupted, "corrupt raw frame"));
	CHECK_FALSE(contains(corrupted, "truncated"));
	std::vector<uint8_t> checksum = good;
	checksum[checksum.size() - 1] ^= 0x01; // the frame's last 4 bytes: XXH64 of the samples
	CHECK(contains(decode_error(checksum), "corrupt raw frame: zstd: "));
}

TEST_CASE("raw frame: absurd sizes and a decompressed size that disagrees are refused before allocation") {
	const std::vector<uint8_t> good = encode(pattern(CV_8UC1, 20, 10));
	const auto with_size = [&](uint32_t p_width, uint32_t p_height) {
		std::vector<uint8_t> bytes = good;
		put_le32(&bytes, 16, p_width);
		put_le32(&bytes, 20, p_height);
		return decode_error(bytes);
	};
	CHECK(contains(with_size(0, 10), "has no pixels (0x10)"));
	CHECK(contains(with_size(20, 0), "has no pixels"));
	CHECK(contains(with_size(40000, 10), "more than RoomProbe reads"));
	CHECK(contains(with_size(0xFFFFFFFFu, 0xFFFFFFFFu), "more than RoomProbe reads"));
	CHECK(contains(with_size(30000, 30000), "more than RoomProbe reads")); // 9e8 pixels, each side allowed
	// 2^28 pixels of 4 float channels: 4 GiB of samples, above the 1 GiB limit.
	std::vector<uint8_t> huge = good;
	put_le32(&huge, 16, 16384);
	put_le32(&huge, 20, 16384);
	huge[14] = 4;
	huge[15] = 4;
	CHECK(contains(decode_error(huge), "bytes of samples, more than RoomProbe reads"));
	// Sizes within the limits that the zstd frame does not hold: refused from the frame's
	// declared size, before the image is allocated.
	const std::string bigger = with_size(20000, 10000);
	CHECK(contains(bigger, "its zstd frame holds 200 bytes, but 20000x10000 pixels of 1 channels of 1 bytes are 200000000"));
	CHECK(contains(with_size(10, 10), "holds 200 bytes, but 10x10 pixels"));
	std::vector<uint8_t> sixteen = good;
	sixteen[14] = 2; // 16-bit: 400 bytes expected
	CHECK(contains(decode_error(sixteen), "of 2 bytes are 400"));
	// A zstd frame that does not say its size (written by a streaming encoder): refused.
	const cv::Mat image = pattern(CV_8UC1, 20, 10);
	ZSTD_CCtx *context = ZSTD_createCCtx();
	std::vector<uint8_t> unknown(kRawFrameHeaderBytes + ZSTD_compressBound(200) + 64);
	std::memcpy(unknown.data(), good.data(), kRawFrameHeaderBytes);
	ZSTD_outBuffer out = { unknown.data() + kRawFrameHeaderBytes, unknown.size() - kRawFrameHeaderBytes, 0 };
	ZSTD_inBuffer in = { image.data, 200, 0 };
	REQUIRE_FALSE(ZSTD_isError(ZSTD_compressStream2(context, &out, &in, ZSTD_e_continue)));
	REQUIRE(ZSTD_compressStream2(context, &out, &in, ZSTD_e_end) == 0);
	ZSTD_freeCCtx(context);
	unknown.resize(kRawFrameHeaderBytes + out.pos);
	for (int i = 0; i < 8; i++) {
		unknown[24 + size_t(i)] = uint8_t(uint64_t(out.pos) >> (8 * i));
	}
	CHECK(contains(decode_error(unknown), "does not say how many bytes it holds"));
	// Garbage where the zstd frame should be.
	std::vector<uint8_t> garbage = good;
	std::memset(garbage.data() + kRawFrameHeaderBytes, 0x41, garbage.size() - kRawFrameHeaderBytes);
	CHECK(contains(decode_error(garbage), "no zstd frame after the header"));
}

TEST_CASE("raw frame: the encoder refuses what it cannot store, and a write replaces the file or names it") {
	std::vector<uint8_t> bytes;
	CHECK(contains(raw_frame_encode(cv::Mat(), 1, &bytes), "empty image"));
	CHECK(contains(raw_frame_encode(cv::Mat(4, 4, CV_64FC1, cv::Scalar(1)), 1, &bytes), "8-bit, 16-bit, half or float"));
	cv::Mat five(4, 4, CV_8UC(5));
	std::memset(five.data, 1, five.total() * five.elemSize());
	CHECK(contains(raw_frame_encode(five, 1, &bytes), "1 to 4 channels"));
	CHECK(contains(raw_frame_encode(cv::Mat(4, 4, CV_8UC1, cv::Scalar(1)), 100, &bytes), "zstd level 100"));
	CHECK(raw_frame_level_problem(1) == "");
	CHECK(raw_frame_level_problem(3) == "");
	CHECK_FALSE(raw_frame_level_problem(1000).empty());

	const std::filesystem::path folder = std::filesystem::path("build") / "test-raw-frame";
	std::error_code ec;
	std::filesystem::remove_all(folder, ec);
	std::filesystem::create_directories(folder / "a_folder");
	const cv::Mat image = pattern(CV_16UC1);
	const std::string path = (folder / "frame.zst").string();
	REQUIRE(raw_frame_write(path, image) == "");
	CHECK(std::filesystem::file_size(path) == encode(image).size());
	const std::string refused = raw_frame_write((folder / "a_folder").string(), image);
	CHECK(contains(refused, (folder / "a_folder").string()));
	const std::string bad = raw_frame_write(path, cv::Mat(), 1);
	CHECK(contains(bad, path + ": an empty image"));
	CHECK(std::filesystem::file_size(path) == encode(image).size()); // left as it was
}
