#include "image_convert.h"

#include <cstring>

using namespace godot;

namespace roomprobe {

Ref<Image> image_from_mat(const cv::Mat &p_mat) {
	Image::Format format;
	switch (p_mat.type()) {
		case CV_8UC1:
			format = Image::FORMAT_L8;
			break;
		case CV_8UC3:
			format = Image::FORMAT_RGB8;
			break;
		case CV_32FC1:
			format = Image::FORMAT_RF;
			break;
		case CV_32FC3:
			format = Image::FORMAT_RGBF;
			break;
		default:
			return Ref<Image>();
	}
	if (p_mat.empty()) {
		return Ref<Image>();
	}
	const cv::Mat packed = p_mat.isContinuous() ? p_mat : p_mat.clone();
	const size_t bytes = packed.total() * packed.elemSize();
	PackedByteArray data;
	data.resize(int64_t(bytes));
	std::memcpy(data.ptrw(), packed.data, bytes);
	return Image::create_from_data(packed.cols, packed.rows, false, format, data);
}

void show_in_texture(const Ref<Image> &p_image, Ref<ImageTexture> &r_texture) {
	if (p_image.is_null()) {
		return;
	}
	if (r_texture.is_valid() && r_texture->get_width() == p_image->get_width() && r_texture->get_height() == p_image->get_height() &&
			r_texture->get_format() == p_image->get_format()) {
		r_texture->update(p_image);
		return;
	}
	r_texture = ImageTexture::create_from_image(p_image);
}

PackedBytesBuffer::PackedBytesBuffer(size_t p_bytes) {
	packed.resize(int64_t(p_bytes));
	write = packed.ptrw();
}

uint8_t *PackedBytesBuffer::data() { return write; }

const uint8_t *PackedBytesBuffer::data() const { return write; }

size_t PackedBytesBuffer::size() const { return size_t(packed.size()); }

Ref<Image> image_from_buffer(const BufferImage &p_image) {
	if (p_image.empty() || !p_image.bytes || (p_image.mat.type() != CV_8UC4 && p_image.mat.type() != CV_16FC4)) {
		return Ref<Image>();
	}
	const Image::Format format = p_image.mat.type() == CV_8UC4 ? Image::FORMAT_RGBA8 : Image::FORMAT_RGBAH;
	return Image::create_from_data(p_image.mat.cols, p_image.mat.rows, false, format, packed_bytes(*p_image.bytes));
}

PixelBufferFactory packed_bytes_buffers() {
	return [](size_t p_bytes) -> std::shared_ptr<PixelBuffer> { return std::make_shared<PackedBytesBuffer>(p_bytes); };
}

PackedByteArray packed_bytes(const PixelBuffer &p_buffer) {
	if (const auto *packed = dynamic_cast<const PackedBytesBuffer *>(&p_buffer)) {
		return packed->bytes();
	}
	PackedByteArray copy;
	copy.resize(int64_t(p_buffer.size()));
	std::memcpy(copy.ptrw(), p_buffer.data(), p_buffer.size());
	return copy;
}

} // namespace roomprobe
