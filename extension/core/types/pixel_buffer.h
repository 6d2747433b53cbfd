#pragma once

// Bytes that a consumer takes without copying them: a map's faces, the camera image and the atlas
// shown are filled on the workers into a buffer the host engine supplies (Godot: a PackedByteArray,
// so the main thread only hands it to the texture), or into a plain vector where no host asks.

#include <opencv2/core/mat.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace roomprobe {

class PixelBuffer {
public:
	virtual ~PixelBuffer() = default;
	virtual uint8_t *data() = 0;
	virtual const uint8_t *data() const = 0;
	virtual size_t size() const = 0;
};

// A buffer of p_bytes bytes, made on the thread that fills it.
using PixelBufferFactory = std::function<std::shared_ptr<PixelBuffer>(size_t p_bytes)>;

class VectorPixelBuffer final : public PixelBuffer {
public:
	explicit VectorPixelBuffer(size_t p_bytes) :
			bytes(p_bytes) {}
	uint8_t *data() override { return bytes.data(); }
	const uint8_t *data() const override { return bytes.data(); }
	size_t size() const override { return bytes.size(); }

private:
	std::vector<uint8_t> bytes;
};

// p_factory's buffer, or a VectorPixelBuffer when p_factory is empty or gives none of that size.
inline std::shared_ptr<PixelBuffer> make_pixel_buffer(const PixelBufferFactory &p_factory, size_t p_bytes) {
	std::shared_ptr<PixelBuffer> made = p_factory ? p_factory(p_bytes) : nullptr;
	if (made && made->size() == p_bytes && (p_bytes == 0 || made->data() != nullptr)) {
		return made;
	}
	return std::make_shared<VectorPixelBuffer>(p_bytes);
}

// An image in a PixelBuffer: the bytes, and a continuous cv::Mat header over them (valid while
// bytes lives; the two travel together).
struct BufferImage {
	std::shared_ptr<const PixelBuffer> bytes;
	cv::Mat mat;
	bool empty() const { return mat.empty(); }
};

// A p_rows x p_cols image of p_type in p_factory's buffer (make_pixel_buffer), for the caller to fill
// through r_image->mat (an OpenCV function given it as its output writes it in place).
inline void make_buffer_image(const PixelBufferFactory &p_factory, int p_rows, int p_cols, int p_type, BufferImage *r_image) {
	const size_t bytes = size_t(p_rows) * size_t(p_cols) * CV_ELEM_SIZE(p_type);
	const std::shared_ptr<PixelBuffer> buffer = make_pixel_buffer(p_factory, bytes);
	r_image->mat = cv::Mat(p_rows, p_cols, p_type, buffer->data());
	r_image->bytes = buffer;
}

} // namespace roomprobe
