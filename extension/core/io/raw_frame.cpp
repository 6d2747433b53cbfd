#include "raw_frame.h"

#include "image_codec.h"
#include "replace_file.h"

#include <zstd.h>

#include <bit>
#include <cstring>
#include <memory>

namespace roomprobe {

// The samples are stored little-endian, as they lie in memory on the machines RoomProbe runs on.
static_assert(std::endian::native == std::endian::little, "raw frame files store little-endian samples; add byte swapping for this machine");

namespace {

// zstd's skippable frames have magic numbers 0x184D2A50 to 0x184D2A5F (RFC 8878, 3.1.2); the
// header is one, so that zstd itself passes over it.
constexpr uint32_t SKIPPABLE_MAGIC = 0x184D2A5E;
constexpr uint32_t ZSTD_FRAME_MAGIC = 0xFD2FB528;
constexpr uint32_t HEADER_CONTENT_BYTES = uint32_t(kRawFrameHeaderBytes) - 8; // after the magic and the length
constexpr char TAG[4] = { 'R', 'P', 'R', 'F' }; // RoomProbe raw frame

// Sample types as stored in byte 14.
enum SampleType : uint8_t {
	SAMPLE_U8 = 1,
	SAMPLE_U16 = 2,
	SAMPLE_F16 = 3,
	SAMPLE_F32 = 4,
};

uint32_t read_le32(const uint8_t *p_bytes) {
	return uint32_t(p_bytes[0]) | (uint32_t(p_bytes[1]) << 8) | (uint32_t(p_bytes[2]) << 16) | (uint32_t(p_bytes[3]) << 24);
}

uint64_t read_le64(const uint8_t *p_bytes) {
	return uint64_t(read_le32(p_bytes)) | (uint64_t(read_le32(p_bytes + 4)) << 32);
}

void write_le32(uint8_t *r_bytes, uint32_t p_value) {
	for (int i = 0; i < 4; i++) {
		r_bytes[i] = uint8_t(p_value >> (8 * i));
	}
}

void write_le64(uint8_t *r_bytes, uint64_t p_value) {
	write_le32(r_bytes, uint32_t(p_value));
	write_le32(r_bytes + 4, uint32_t(p_value >> 32));
}

int depth_of(uint8_t p_type) {
	switch (p_type) {
		case SAMPLE_U8:
			return CV_8U;
		case SAMPLE_U16:
			return CV_16U;
		case SAMPLE_F16:
			return CV_16F;
		case SAMPLE_F32:
			return CV_32F;
		default:
			return -1;
	}
}

uint8_t type_of(int p_depth) {
	switch (p_depth) {
		case CV_8U:
			return SAMPLE_U8;
		case CV_16U:
			return SAMPLE_U16;
		case CV_16F:
			return SAMPLE_F16;
		case CV_32F:
			return SAMPLE_F32;
		default:
			return 0;
	}
}

// One compression and one decompression context per thread, kept: making one costs more than a
// frame's decoding does at these sizes.
struct ZstdContexts {
	ZSTD_CCtx *compress = nullptr;
	ZSTD_DCtx *decompress = nullptr;
	~ZstdContexts() {
		ZSTD_freeCCtx(compress);
		ZSTD_freeDCtx(decompress);
	}
};

ZstdContexts &contexts() {
	thread_local ZstdContexts held;
	return held;
}

} // namespace

uint64_t RawFrameHeader::sample_bytes() const {
	const int bytes = depth == CV_8U ? 1 : depth == CV_32F ? 4 : 2;
	return uint64_t(width) * uint64_t(height) * uint64_t(channels) * uint64_t(bytes);
}

bool raw_frame_signature(const uint8_t *p_bytes, size_t p_size) {
	return p_size >= 12 && read_le32(p_bytes) == SKIPPABLE_MAGIC && read_le32(p_bytes + 4) == HEADER_CONTENT_BYTES &&
			std::memcmp(p_bytes + 8, TAG, 4) == 0;
}

bool zstd_magic(const uint8_t *p_bytes, size_t p_size) {
	if (p_size < 4) {
		return false;
	}
	const uint32_t magic = read_le32(p_bytes);
	return magic == ZSTD_FRAME_MAGIC || (magic & 0xFFFFFFF0u) == (SKIPPABLE_MAGIC & 0xFFFFFFF0u);
}

std::string raw_frame_parse_header(const uint8_t *p_bytes, size_t p_size, RawFrameHeader *r_header) {
	if (p_size >= 4 && read_le32(p_bytes) == ZSTD_FRAME_MAGIC) {
		return "not a RoomProbe raw frame: a plain zstd file, without the frame header that says what the samples are";
	}
	if (p_size < 12 || !raw_frame_signature(p_bytes, p_size)) {
		if (p_size < 12 && p_size >= 4 && read_le32(p_bytes) == SKIPPABLE_MAGIC) {
			return "truncated: the raw frame ends at byte " + std::to_string(p_size) + ", inside its " + std::to_string(kRawFrameHeaderBytes) + "-byte header";
		}
		return std::string("not a RoomProbe raw frame (no 'RPRF' header)") + (p_size == 0 ? " (empty file)" : "");
	}
	if (p_size < kRawFrameHeaderBytes) {
		return "truncated: the raw frame ends at byte " + std::to_string(p_size) + ", inside its " + std::to_string(kRawFrameHeaderBytes) + "-byte header";
	}
	const int version = int(p_bytes[12]) | (int(p_bytes[13]) << 8);
	if (version != kRawFrameVersion) {
		return "raw frame format version " + std::to_string(version) + "; this RoomProbe reads version " + std::to_string(kRawFrameVersion);
	}
	RawFrameHeader header;
	header.depth = depth_of(p_bytes[14]);
	header.channels = p_bytes[15];
	const uint32_t width = read_le32(p_bytes + 16);
	const uint32_t height = read_le32(p_bytes + 20);
	header.data_bytes = read_le64(p_bytes + 24);
	if (header.depth < 0) {
		return "corrupt raw frame: sample type " + std::to_string(p_bytes[14]) + " (1: 8-bit, 2: 16-bit, 3: half, 4: float)";
	}
	if (header.channels < 1 || header.channels > 4) {
		return "corrupt raw frame: " + std::to_string(header.channels) + " channels (1 to 4)";
	}
	const std::string size = image_size_problem(width, height);
	if (!size.empty()) {
		return "corrupt raw frame: the image " + size;
	}
	header.width = int(width);
	header.height = int(height);
	if (header.sample_bytes() > kRawFrameMaxBytes) {
		return "corrupt raw frame: " + std::to_string(header.sample_bytes()) + " bytes of samples, more than RoomProbe reads (" +
				std::to_string(kRawFrameMaxBytes) + ")";
	}
	*r_header = header;
	return "";
}

std::string raw_frame_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image) {
	RawFrameHeader header;
	const std::string problem = raw_frame_parse_header(p_bytes, p_size, &header);
	if (!problem.empty()) {
		return problem;
	}
	const uint64_t available = p_size - kRawFrameHeaderBytes;
	if (available < header.data_bytes) {
		return "truncated: the raw frame ends at byte " + std::to_string(p_size) + "; its header says " +
				std::to_string(kRawFrameHeaderBytes + header.data_bytes) + " bytes";
	}
	if (available > header.data_bytes) {
		return "corrupt raw frame: " + std::to_string(available - header.data_bytes) + " bytes after its zstd data (the header says " +
				std::to_string(kRawFrameHeaderBytes + header.data_bytes) + " bytes in all)";
	}
	const uint8_t *data = p_bytes + kRawFrameHeaderBytes;
	const size_t data_size = size_t(header.data_bytes);
	const unsigned long long content = ZSTD_getFrameContentSize(data, data_size);
	if (content == ZSTD_CONTENTSIZE_ERROR) {
		return "corrupt raw frame: no zstd frame after the header";
	}
	if (content == ZSTD_CONTENTSIZE_UNKNOWN) {
		return "corrupt raw frame: its zstd frame does not say how many bytes it holds";
	}
	const uint64_t expected = header.sample_bytes();
	if (content != expected) {
		return "corrupt raw frame: its zstd frame holds " + std::to_string(content) + " bytes, but " + std::to_string(header.width) + "x" +
				std::to_string(header.height) + " pixels of " + std::to_string(header.channels) + " channels of " +
				std::to_string(expected / (uint64_t(header.width) * header.height * header.channels)) + " bytes are " + std::to_string(expected);
	}
	ZstdContexts &held = contexts();
	if (held.decompress == nullptr && (held.decompress = ZSTD_createDCtx()) == nullptr) {
		return "out of memory for the zstd decoder";
	}
	cv::Mat image(header.height, header.width, header.cv_type());
	const size_t written = ZSTD_decompressDCtx(held.decompress, image.data, size_t(expected), data, data_size);
	if (ZSTD_isError(written)) {
		return std::string("corrupt raw frame: zstd: ") + ZSTD_getErrorName(written);
	}
	if (written != expected) {
		return "corrupt raw frame: its zstd data decompressed to " + std::to_string(written) + " bytes, not " + std::to_string(expected);
	}
	*r_image = image;
	return "";
}

std::string raw_frame_level_problem(int p_level) {
	if (p_level < ZSTD_minCLevel() || p_level > ZSTD_maxCLevel()) {
		return "zstd level " + std::to_string(p_level) + " is not one of zstd's (" + std::to_string(ZSTD_minCLevel()) + " to " +
				std::to_string(ZSTD_maxCLevel()) + ")";
	}
	return "";
}

std::string raw_frame_encode(const cv::Mat &p_image, int p_level, std::vector<uint8_t> *r_bytes) {
	if (p_image.empty()) {
		return "an empty image cannot be written as a raw frame";
	}
	const uint8_t type = type_of(p_image.depth());
	if (type == 0 || p_image.channels() > 4) {
		return "a raw frame takes 8-bit, 16-bit, half or float images of 1 to 4 channels (got depth " + std::to_string(p_image.depth()) + ", " +
				std::to_string(p_image.channels()) + " channels)";
	}
	const std::string size = image_size_problem(p_image.cols, p_image.rows);
	if (!size.empty()) {
		return "the image " + size;
	}
	const std::string level = raw_frame_level_problem(p_level);
	if (!level.empty()) {
		return level;
	}
	const cv::Mat image = p_image.isContinuous() ? p_image : p_image.clone();
	const size_t sample_bytes = image.total() * image.elemSize();
	if (sample_bytes > kRawFrameMaxBytes) {
		return "the image holds " + std::to_string(sample_bytes) + " bytes of samples, more than a raw frame takes (" + std::to_string(kRawFrameMaxBytes) + ")";
	}
	ZstdContexts &held = contexts();
	if (held.compress == nullptr && (held.compress = ZSTD_createCCtx()) == nullptr) {
		return "out of memory for the zstd encoder";
	}
	ZSTD_CCtx_reset(held.compress, ZSTD_reset_session_and_parameters);
	size_t set = ZSTD_CCtx_setParameter(held.compress, ZSTD_c_compressionLevel, p_level);
	if (!ZSTD_isError(set)) {
		set = ZSTD_CCtx_setParameter(held.compress, ZSTD_c_checksumFlag, 1); // a flipped bit is an error, not a wrong pixel
	}
	if (ZSTD_isError(set)) {
		return std::string("zstd: ") + ZSTD_getErrorName(set);
	}
	r_bytes->resize(kRawFrameHeaderBytes + ZSTD_compressBound(sample_bytes));
	uint8_t *header = r_bytes->data();
	write_le32(header, SKIPPABLE_MAGIC);
	write_le32(header + 4, HEADER_CONTENT_BYTES);
	std::memcpy(header + 8, TAG, 4);
	header[12] = uint8_t(kRawFrameVersion);
	header[13] = uint8_t(kRawFrameVersion >> 8);
	header[14] = type;
	header[15] = uint8_t(image.channels());
	write_le32(header + 16, uint32_t(image.cols));
	write_le32(header + 20, uint32_t(image.rows));
	const size_t compressed = ZSTD_compress2(held.compress, r_bytes->data() + kRawFrameHeaderBytes, r_bytes->size() - kRawFrameHeaderBytes, image.data, sample_bytes);
	if (ZSTD_isError(compressed)) {
		r_bytes->clear();
		return std::string("zstd compression failed: ") + ZSTD_getErrorName(compressed);
	}
	write_le64(r_bytes->data() + 24, compressed);
	r_bytes->resize(kRawFrameHeaderBytes + compressed);
	return "";
}

std::string raw_frame_write(const std::string &p_path, const cv::Mat &p_image, int p_level) {
	std::vector<uint8_t> bytes;
	const std::string error = raw_frame_encode(p_image, p_level, &bytes);
	if (!error.empty()) {
		return p_path + ": " + error;
	}
	return replace_file(p_path, bytes.data(), bytes.size());
}

} // namespace roomprobe
