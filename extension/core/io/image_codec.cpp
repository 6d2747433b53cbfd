#include "image_codec.h"

// clang-format off
#include <cstdio> // jpeglib.h needs FILE
#include <jpeglib.h>
#include <jerror.h>
// clang-format on
#include <png.h>

#include "input_path.h"
#include "opencv.h"
#include "replace_file.h"

#include <csetjmp>
#include <cstring>
#include <fstream>
#include <iterator>

namespace roomprobe {

// libpng and libjpeg report errors by longjmp. Each decoder below keeps to plain data between its
// setjmp and the library calls that may jump: the image is made by a helper (its temporaries are
// gone before the next library call) into a cv::Mat that lives in the caller's frame.

namespace {

struct CodecError {
	std::jmp_buf jump;
	char message[200] = { 0 };
};

// No std::string may outlive a call in the frames that setjmp returns to: this one is gone here.
bool size_ok(int64_t p_width, int64_t p_height, CodecError *r_error) {
	const std::string problem = image_size_problem(p_width, p_height);
	std::snprintf(r_error->message, sizeof(r_error->message), "%s", problem.c_str());
	return problem.empty();
}

void make_image(cv::Mat *r_image, int p_rows, int p_cols, int p_type) {
	*r_image = cv::Mat(p_rows, p_cols, p_type);
}

// ---------------------------------------------------------------- PNG

struct PngSource {
	const uint8_t *bytes;
	size_t size;
	size_t offset;
};

[[noreturn]] void png_on_error(png_structp p_png, png_const_charp p_message) {
	CodecError *error = static_cast<CodecError *>(png_get_error_ptr(p_png));
	std::snprintf(error->message, sizeof(error->message), "%s", p_message);
	std::longjmp(error->jump, 1);
}

void png_on_warning(png_structp, png_const_charp) {}

void png_read_bytes(png_structp p_png, png_bytep r_out, png_size_t p_count) {
	PngSource *source = static_cast<PngSource *>(png_get_io_ptr(p_png));
	if (p_count > source->size - source->offset) {
		png_error(p_png, "truncated (the file ends inside the image data)");
	}
	std::memcpy(r_out, source->bytes + source->offset, p_count);
	source->offset += p_count;
}

// Decodes into *r_image; false with r_error->message set on failure.
bool png_decode_into(png_structp p_png, png_infop p_info, PngSource *p_source, CodecError *r_error, cv::Mat *r_image) {
	if (setjmp(r_error->jump)) {
		return false;
	}
	png_set_read_fn(p_png, p_source, png_read_bytes);
	png_set_user_limits(p_png, kImageMaxSidePx, kImageMaxSidePx);
	png_read_info(p_png, p_info);
	const png_uint_32 width = png_get_image_width(p_png, p_info);
	const png_uint_32 height = png_get_image_height(p_png, p_info);
	const int color_type = png_get_color_type(p_png, p_info);
	const int bit_depth = png_get_bit_depth(p_png, p_info);
	if (!size_ok(width, height, r_error)) {
		return false;
	}
	if (color_type == PNG_COLOR_TYPE_PALETTE) {
		png_set_palette_to_rgb(p_png);
	}
	if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) {
		png_set_expand_gray_1_2_4_to_8(p_png);
	}
	if (png_get_valid(p_png, p_info, PNG_INFO_tRNS)) {
		png_set_tRNS_to_alpha(p_png);
	}
	if (color_type == PNG_COLOR_TYPE_GRAY_ALPHA || (color_type == PNG_COLOR_TYPE_GRAY && png_get_valid(p_png, p_info, PNG_INFO_tRNS))) {
		png_set_gray_to_rgb(p_png);
	}
	if (bit_depth == 16) {
		png_set_swap(p_png); // PNG is big-endian, cv::Mat's 16-bit pixels are the host's (x86: little)
	}
	png_set_bgr(p_png);
	const int passes = png_set_interlace_handling(p_png);
	png_read_update_info(p_png, p_info);
	const int channels = png_get_channels(p_png, p_info);
	const int depth = png_get_bit_depth(p_png, p_info) == 16 ? CV_16U : CV_8U;
	if (channels < 1 || channels > 4) {
		std::snprintf(r_error->message, sizeof(r_error->message), "has %d channels after expansion", channels);
		return false;
	}
	make_image(r_image, int(height), int(width), CV_MAKETYPE(depth, channels));
	for (int pass = 0; pass < passes; ++pass) {
		for (png_uint_32 y = 0; y < height; ++y) {
			png_read_row(p_png, r_image->ptr<png_byte>(int(y)), nullptr);
		}
	}
	png_read_end(p_png, nullptr);
	return true;
}

struct PngSink {
	std::vector<uint8_t> *bytes;
};

void png_write_bytes(png_structp p_png, png_bytep p_data, png_size_t p_count) {
	PngSink *sink = static_cast<PngSink *>(png_get_io_ptr(p_png));
	sink->bytes->insert(sink->bytes->end(), p_data, p_data + p_count);
}

void png_flush(png_structp) {}

bool png_encode_from(png_structp p_png, png_infop p_info, const cv::Mat &p_image, PngSink *p_sink, CodecError *r_error) {
	if (setjmp(r_error->jump)) {
		return false;
	}
	static constexpr int kColourTypes[5] = { 0, PNG_COLOR_TYPE_GRAY, 0, PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA };
	const int bit_depth = p_image.depth() == CV_16U ? 16 : 8;
	png_set_write_fn(p_png, p_sink, png_write_bytes, png_flush);
	// Level 1: the synthetic renderer and the recorder write many frames, and size matters less.
	png_set_compression_level(p_png, 1);
	png_set_IHDR(p_png, p_info, png_uint_32(p_image.cols), png_uint_32(p_image.rows), bit_depth, kColourTypes[p_image.channels()],
			PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	png_write_info(p_png, p_info);
	if (bit_depth == 16) {
		png_set_swap(p_png);
	}
	png_set_bgr(p_png);
	for (int y = 0; y < p_image.rows; ++y) {
		png_write_row(p_png, p_image.ptr<png_byte>(y));
	}
	png_write_end(p_png, p_info);
	return true;
}

// ---------------------------------------------------------------- JPEG

struct JpegError {
	jpeg_error_mgr manager; // first: libjpeg hands back a pointer to it
	CodecError codec;
	bool truncated = false;
};

[[noreturn]] void jpeg_on_error(j_common_ptr p_info) {
	JpegError *error = reinterpret_cast<JpegError *>(p_info->err);
	char text[JMSG_LENGTH_MAX];
	(*p_info->err->format_message)(p_info, text);
	std::snprintf(error->codec.message, sizeof(error->codec.message), "%s", text);
	std::longjmp(error->codec.jump, 1);
}

// Warnings (extraneous bytes, say) are not errors, but a file that ends early is: libjpeg would
// fill the rest with gray and call it a frame.
void jpeg_on_message(j_common_ptr p_info, int p_level) {
	if (p_level < 0 && p_info->err->msg_code == JWRN_JPEG_EOF) {
		reinterpret_cast<JpegError *>(p_info->err)->truncated = true;
	}
}

bool jpeg_decode_into(jpeg_decompress_struct *p_jpeg, JpegError *r_error, const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image) {
	if (setjmp(r_error->codec.jump)) {
		return false;
	}
	jpeg_create_decompress(p_jpeg);
	jpeg_mem_src(p_jpeg, p_bytes, static_cast<unsigned long>(p_size));
	jpeg_read_header(p_jpeg, TRUE);
	if (!size_ok(p_jpeg->image_width, p_jpeg->image_height, &r_error->codec)) {
		return false;
	}
	if (p_jpeg->jpeg_color_space == JCS_CMYK || p_jpeg->jpeg_color_space == JCS_YCCK) {
		std::snprintf(r_error->codec.message, sizeof(r_error->codec.message), "is a CMYK JPEG; RoomProbe reads gray and colour JPEGs");
		return false;
	}
	const bool gray = p_jpeg->num_components == 1;
	p_jpeg->out_color_space = gray ? JCS_GRAYSCALE : JCS_EXT_BGR;
	jpeg_start_decompress(p_jpeg);
	make_image(r_image, int(p_jpeg->output_height), int(p_jpeg->output_width), gray ? CV_8UC1 : CV_8UC3);
	while (p_jpeg->output_scanline < p_jpeg->output_height) {
		JSAMPROW row = r_image->ptr<JSAMPLE>(int(p_jpeg->output_scanline));
		jpeg_read_scanlines(p_jpeg, &row, 1);
	}
	jpeg_finish_decompress(p_jpeg);
	return true;
}

bool starts_with(const std::vector<uint8_t> &p_bytes, std::initializer_list<uint8_t> p_magic) {
	return p_bytes.size() >= p_magic.size() && std::equal(p_magic.begin(), p_magic.end(), p_bytes.begin());
}

} // namespace

std::string image_size_problem(int64_t p_width, int64_t p_height) {
	if (p_width <= 0 || p_height <= 0) {
		return "has no pixels (" + std::to_string(p_width) + "x" + std::to_string(p_height) + ")";
	}
	if (p_width > kImageMaxSidePx || p_height > kImageMaxSidePx || p_width * p_height > kImageMaxPixels) {
		return "is " + std::to_string(p_width) + "x" + std::to_string(p_height) + " pixels, more than RoomProbe reads (" +
				std::to_string(kImageMaxSidePx) + " a side, " + std::to_string(kImageMaxPixels) + " in all)";
	}
	return "";
}

std::string png_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image) {
	if (p_size < 8 || png_sig_cmp(p_bytes, 0, 8) != 0) {
		return "not a PNG (no PNG signature)";
	}
	CodecError error;
	png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, png_on_error, png_on_warning);
	png_infop info = png ? png_create_info_struct(png) : nullptr;
	if (!info) {
		png_destroy_read_struct(&png, nullptr, nullptr);
		return "out of memory for the PNG decoder";
	}
	PngSource source = { p_bytes, p_size, 0 };
	cv::Mat image;
	const bool ok = png_decode_into(png, info, &source, &error, &image);
	png_destroy_read_struct(&png, &info, nullptr);
	if (!ok) {
		return std::string("corrupt PNG: ") + error.message;
	}
	*r_image = image;
	return "";
}

std::string jpeg_decode(const uint8_t *p_bytes, size_t p_size, cv::Mat *r_image) {
	if (p_size < 3 || p_bytes[0] != 0xFF || p_bytes[1] != 0xD8 || p_bytes[2] != 0xFF) {
		return "not a JPEG (no start-of-image marker)";
	}
	jpeg_decompress_struct jpeg;
	JpegError error;
	jpeg.err = jpeg_std_error(&error.manager);
	error.manager.error_exit = jpeg_on_error;
	error.manager.emit_message = jpeg_on_message;
	cv::Mat image;
	const bool ok = jpeg_decode_into(&jpeg, &error, p_bytes, p_size, &image);
	jpeg_destroy_decompress(&jpeg);
	if (!ok) {
		return std::string("corrupt JPEG: ") + error.codec.message;
	}
	if (error.truncated) {
		return "corrupt JPEG: truncated (the file ends inside the image data)";
	}
	*r_image = image;
	return "";
}

std::string png_encode(const cv::Mat &p_image, std::vector<uint8_t> *r_bytes) {
	if (p_image.empty()) {
		return "an empty image cannot be written as PNG";
	}
	if ((p_image.depth() != CV_8U && p_image.depth() != CV_16U) || p_image.channels() == 2 || p_image.channels() > 4) {
		return "PNG takes 8- or 16-bit images of 1, 3 or 4 channels (got depth " + std::to_string(p_image.depth()) + ", " +
				std::to_string(p_image.channels()) + " channels)";
	}
	const cv::Mat image = p_image.isContinuous() ? p_image : p_image.clone();
	CodecError error;
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, png_on_error, png_on_warning);
	png_infop info = png ? png_create_info_struct(png) : nullptr;
	if (!info) {
		png_destroy_write_struct(&png, nullptr);
		return "out of memory for the PNG encoder";
	}
	r_bytes->clear();
	PngSink sink = { r_bytes };
	const bool ok = png_encode_from(png, info, image, &sink, &error);
	png_destroy_write_struct(&png, &info);
	if (!ok) {
		return std::string("PNG encoding failed: ") + error.message;
	}
	return "";
}

std::string read_file_bytes(const std::string &p_path, std::vector<uint8_t> *r_bytes) {
	// A device or a pipe is named for what it is, never read (/dev/zero never ends, a pipe blocks).
	const std::string not_a_file = input_file_problem(p_path);
	if (!not_a_file.empty()) {
		return not_a_file;
	}
	std::ifstream file(p_path, std::ios::binary);
	if (!file) {
		return p_path + ": cannot be opened for reading";
	}
	// A file whose size is known is read in one call (a frame of a megabyte byte by byte took a
	// millisecond); one that grew since is read to the size seen, one that shrank to its end.
	file.seekg(0, std::ios::end);
	const std::streamoff size = file.tellg();
	file.seekg(0);
	if (size >= 0 && file) {
		r_bytes->resize(size_t(size));
		file.read(reinterpret_cast<char *>(r_bytes->data()), std::streamsize(size));
		r_bytes->resize(size_t(file.gcount()));
	} else { // a pipe, say
		file.clear();
		r_bytes->assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
	}
	if (file.bad()) {
		return p_path + ": read error";
	}
	return "";
}

std::string image_read(const std::string &p_path, ImageReadMode p_mode, cv::Mat *r_image) {
	std::vector<uint8_t> bytes;
	std::string error = read_file_bytes(p_path, &bytes);
	if (!error.empty()) {
		return error;
	}
	cv::Mat image;
	if (starts_with(bytes, { 0x89, 'P', 'N', 'G' })) {
		error = png_decode(bytes.data(), bytes.size(), &image);
	} else if (starts_with(bytes, { 0xFF, 0xD8, 0xFF })) {
		error = jpeg_decode(bytes.data(), bytes.size(), &image);
	} else {
		return p_path + ": neither a PNG nor a JPEG" + (bytes.empty() ? std::string(" (empty file)") : std::string());
	}
	if (!error.empty()) {
		return p_path + ": " + error;
	}
	if (p_mode != ImageReadMode::Unchanged) {
		if (image.depth() == CV_16U) {
			image.convertTo(image, CV_8U, 1.0 / 257.0);
		}
		const int channels = image.channels();
		if (p_mode == ImageReadMode::Gray8 && channels != 1) {
			cv::cvtColor(image, image, channels == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
		} else if (p_mode == ImageReadMode::Bgr8 && channels != 3) {
			cv::cvtColor(image, image, channels == 4 ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
		}
	}
	*r_image = image;
	return "";
}

std::string png_write(const std::string &p_path, const cv::Mat &p_image) {
	std::vector<uint8_t> bytes;
	const std::string error = png_encode(p_image, &bytes);
	if (!error.empty()) {
		return p_path + ": " + error;
	}
	// Whole or not at all: no half image is left behind, and the index never lists one.
	return replace_file(p_path, bytes.data(), bytes.size());
}

} // namespace roomprobe
