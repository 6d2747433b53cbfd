// io/image_codec: PNG and JPEG through libpng and libjpeg, checked against OpenCV's imgcodecs
// (the reference the conventions come from) and against broken input.
#include "io/image_codec.h"
#include "io/opencv.h"

#include <doctest/doctest.h>

// OpenCV's codecs, for fixtures and as the reference (io/opencv.h leaves imgcodecs out).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace roomprobe;

namespace {

cv::Mat pattern(int p_type) {
	cv::Mat image(37, 53, p_type);
	cv::RNG rng(7);
	rng.fill(image, cv::RNG::UNIFORM, 0, image.depth() == CV_16U ? 65536 : 256);
	return image;
}

double max_difference(const cv::Mat &p_a, const cv::Mat &p_b) {
	REQUIRE(p_a.type() == p_b.type());
	REQUIRE(p_a.size() == p_b.size());
	return cv::norm(p_a, p_b, cv::NORM_INF);
}

// PNG's chunk CRC (ISO 3309), to forge a valid header.
uint32_t crc32(const uint8_t *p_bytes, size_t p_size) {
	uint32_t crc = 0xFFFFFFFFu;
	for (size_t i = 0; i < p_size; ++i) {
		crc ^= p_bytes[i];
		for (int k = 0; k < 8; ++k) {
			crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
		}
	}
	return ~crc;
}

} // namespace

TEST_CASE("image codec: PNG round trips are exact and read as OpenCV reads them, 8 and 16 bits, 1, 3 and 4 channels") {
	for (const int type : { CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3 }) {
		CAPTURE(type);
		const cv::Mat image = pattern(type);
		std::vector<uint8_t> ours;
		REQUIRE(png_encode(image, &ours) == "");
		cv::Mat back;
		REQUIRE(png_decode(ours.data(), ours.size(), &back) == "");
		CHECK(max_difference(back, image) == 0.0);
		// OpenCV reads our bytes the same, and we read OpenCV's the same: the same conventions.
		CHECK(max_difference(cv::imdecode(ours, cv::IMREAD_UNCHANGED), image) == 0.0);
		std::vector<uint8_t> theirs;
		REQUIRE(cv::imencode(".png", image, theirs));
		REQUIRE(png_decode(theirs.data(), theirs.size(), &back) == "");
		CHECK(max_difference(back, image) == 0.0);
	}
}

TEST_CASE("image codec: JPEG decodes as OpenCV decodes it, gray and colour") {
	for (const int type : { CV_8UC1, CV_8UC3 }) {
		CAPTURE(type);
		cv::Mat image = pattern(type);
		cv::GaussianBlur(image, image, cv::Size(5, 5), 2.0);
		std::vector<uint8_t> bytes;
		REQUIRE(cv::imencode(".jpg", image, bytes));
		cv::Mat ours;
		REQUIRE(jpeg_decode(bytes.data(), bytes.size(), &ours) == "");
		// The same libjpeg and the same default IDCT: within 1 of OpenCV's decode.
		CHECK(max_difference(ours, cv::imdecode(bytes, cv::IMREAD_UNCHANGED)) <= 1.0);
	}
}

TEST_CASE("image codec: broken, truncated and oversized files are refused with their reason") {
	const cv::Mat image = pattern(CV_8UC3);
	std::vector<uint8_t> bytes;
	REQUIRE(png_encode(image, &bytes) == "");
	cv::Mat out;
	CHECK(png_decode(bytes.data(), 20, &out).find("corrupt PNG") == 0);
	std::vector<uint8_t> flipped = bytes;
	flipped[flipped.size() / 2] ^= 0xFF; // a bad CRC or bad deflate data
	CHECK(png_decode(flipped.data(), flipped.size(), &out).find("corrupt PNG") == 0);
	CHECK(png_decode(bytes.data() + 1, bytes.size() - 1, &out).find("not a PNG") == 0);
	// A header claiming 100000 x 100000 pixels: refused before any allocation.
	std::vector<uint8_t> huge = bytes;
	for (int i = 0; i < 2; ++i) {
		const uint32_t side = 100000;
		for (int b = 0; b < 4; ++b) {
			huge[16 + 4 * i + b] = uint8_t(side >> (24 - 8 * b));
		}
	}
	const uint32_t crc = crc32(huge.data() + 12, 17); // over "IHDR" and its 13 bytes
	for (int b = 0; b < 4; ++b) {
		huge[29 + b] = uint8_t(crc >> (24 - 8 * b));
	}
	const std::string huge_error = png_decode(huge.data(), huge.size(), &out);
	CHECK(huge_error.find("corrupt PNG") == 0);
	CHECK(huge_error.find("CRC") == std::string::npos); // refused for its size, not its checksum
	CHECK(out.empty());
	std::vector<uint8_t> jpeg;
	REQUIRE(cv::imencode(".jpg", image, jpeg));
	CHECK(jpeg_decode(jpeg.data(), jpeg.size() / 3, &out).find("corrupt JPEG") == 0);
	CHECK(png_encode(cv::Mat(4, 4, CV_32FC1), &bytes).find("8- or 16-bit") != std::string::npos);

	const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("roomprobe_codec_" + std::to_string(::getpid()));
	std::filesystem::create_directories(dir);
	std::ofstream((dir / "text.png").string()) << "hello";
	CHECK(image_read((dir / "text.png").string(), ImageReadMode::Unchanged, &out).find("neither a PNG nor a JPEG") != std::string::npos);
	CHECK(image_read((dir / "missing.png").string(), ImageReadMode::Unchanged, &out).find("missing.png: missing") != std::string::npos);
	// Issue #38: a device or a folder is named for what it is, never read (/dev/zero was "(empty file)").
	CHECK(image_read("/dev/zero", ImageReadMode::Unchanged, &out) == "/dev/zero: not a regular file (a character device)");
	CHECK(image_read(dir.string(), ImageReadMode::Unchanged, &out) == dir.string() + ": a folder, not a file");
	REQUIRE(png_write((dir / "c.png").string(), image) == "");
	REQUIRE(image_read((dir / "c.png").string(), ImageReadMode::Gray8, &out) == "");
	cv::Mat gray;
	cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
	CHECK(max_difference(out, gray) == 0.0);
	CHECK(png_write((dir / "no/such/folder.png").string(), image).find("cannot be opened for writing") != std::string::npos);
	std::filesystem::remove_all(dir);
}
