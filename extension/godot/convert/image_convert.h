#pragma once
// Core images (cv::Mat) to Godot images and textures. The one place for these conversions.

#include <types/pixel_buffer.h>

#include <opencv2/core/mat.hpp>

#include <rp_godot/godot.h>

namespace roomprobe {

// CV_8UC1 -> L8, CV_8UC3 (R, G, B order) -> RGB8, CV_32FC1 -> RF, CV_32FC3 -> RGBF. An
// unsupported type or an empty matrix gives a null Ref. Godot's renderer converts RGB8 and RGBF
// to their RGBA forms on the calling thread at each upload: images shown every frame are made
// as BufferImages instead (image_from_buffer).
godot::Ref<godot::Image> image_from_mat(const cv::Mat &p_mat);
// A worker's image for display: CV_8UC4 -> RGBA8, CV_16FC4 -> RGBAH, its bytes shared when they
// are a PackedBytesBuffer (else copied). Other types, or none: a null Ref.
godot::Ref<godot::Image> image_from_buffer(const BufferImage &p_image);
// Puts p_image into r_texture, updating it in place when size and format are unchanged
// (no new GPU texture per frame), creating it otherwise.
void show_in_texture(const godot::Ref<godot::Image> &p_image, godot::Ref<godot::ImageTexture> &r_texture);

// The engine's workers fill the images for display straight into these
// (LiveRoomConfig::display_buffers), so the main thread hands the bytes to an Image without
// copying them.
class PackedBytesBuffer final : public PixelBuffer {
public:
	explicit PackedBytesBuffer(size_t p_bytes);
	uint8_t *data() override;
	const uint8_t *data() const override;
	size_t size() const override;
	const godot::PackedByteArray &bytes() const { return packed; }

private:
	godot::PackedByteArray packed;
	uint8_t *write = nullptr; // taken once: the array is not shared until the map is published
};
PixelBufferFactory packed_bytes_buffers();
// p_buffer's bytes as a PackedByteArray: shared when the workers filled a PackedBytesBuffer,
// else copied.
godot::PackedByteArray packed_bytes(const PixelBuffer &p_buffer);

} // namespace roomprobe
