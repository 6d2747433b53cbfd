#include "camera_feed_convert.h"

#include <opencv2/imgproc.hpp>

#include <cstring>

using namespace godot;

namespace roomprobe {

namespace {

// An Image as an 8-bit matrix of p_channels channels. One- and two-channel images keep their
// bytes (a Y plane comes back as R8 or L8, CbCr as RG8); others are converted (to R8, RG8, RGB8).
cv::Mat mat_of(Ref<Image> p_image, int p_channels) {
	const Image::Format format = p_image->get_format();
	const bool as_is = (p_channels == 1 && (format == Image::FORMAT_L8 || format == Image::FORMAT_R8)) ||
			(p_channels == 2 && (format == Image::FORMAT_RG8 || format == Image::FORMAT_LA8)) || (p_channels == 3 && format == Image::FORMAT_RGB8);
	if (!as_is) {
		p_image = p_image->duplicate();
		p_image->convert(p_channels == 1 ? Image::FORMAT_R8 : p_channels == 2 ? Image::FORMAT_RG8 : Image::FORMAT_RGB8);
	}
	const PackedByteArray bytes = p_image->get_data();
	cv::Mat mat(int(p_image->get_height()), int(p_image->get_width()), CV_8UC(p_channels));
	if (size_t(bytes.size()) != mat.total() * mat.elemSize()) {
		return cv::Mat();
	}
	std::memcpy(mat.data, bytes.ptr(), mat.total() * mat.elemSize());
	return mat;
}

// YUY2 (4:2:2) as Godot's feeds hand it to set_ycbcr_image: a two-channel image of the frame's
// size, Y in the first channel, Cb and Cr taking turns in the second (Cb at even columns).
cv::Mat ycbcr_of_yuy2(const cv::Mat &p_yuy2) {
	cv::Mat ycbcr(p_yuy2.size(), CV_8UC3);
	for (int y = 0; y < p_yuy2.rows; y++) {
		const cv::Vec2b *in = p_yuy2.ptr<cv::Vec2b>(y);
		cv::Vec3b *out = ycbcr.ptr<cv::Vec3b>(y);
		for (int x = 0; x < p_yuy2.cols; x++) {
			const int pair = x & ~1;
			const uint8_t cb = in[pair][1];
			const uint8_t cr = pair + 1 < p_yuy2.cols ? in[pair + 1][1] : uint8_t(128);
			out[x] = cv::Vec3b(in[x][0], cb, cr);
		}
	}
	return ycbcr;
}

// Full-range Y, Cb, Cr to R, G, B with the BT.709 matrix, as Godot's camera background shader does.
cv::Mat rgb_of_ycbcr(const cv::Mat &p_ycbcr) {
	cv::Mat rgb;
	const cv::Matx34f to_rgb(1.0f, 0.0f, 1.57481f, -1.57481f * 128.0f, //
			1.0f, -0.18732f, -0.46813f, (0.18732f + 0.46813f) * 128.0f, //
			1.0f, 1.85560f, 0.0f, -1.85560f * 128.0f);
	cv::transform(p_ycbcr, rgb, to_rgb); // saturates to 0..255
	return rgb;
}

} // namespace

void CameraFeedReader::reset() {
	feed_id = -1;
	for (Ref<CameraTexture> &texture : textures) {
		texture.unref();
	}
}

Ref<Image> CameraFeedReader::texture_image(int64_t p_feed_id, CameraServer::FeedImage p_which) {
	if (p_feed_id != feed_id) {
		reset();
		feed_id = p_feed_id;
	}
	Ref<CameraTexture> &texture = textures[int(p_which)];
	if (texture.is_null()) {
		texture.instantiate();
		texture->set_camera_feed_id(p_feed_id);
		texture->set_which_feed(p_which);
	}
	return texture->get_image();
}

cv::Mat CameraFeedReader::read(const Ref<CameraFeed> &p_feed, std::string *r_error) {
	const int64_t id = p_feed->get_id();
	const auto readable = [&](const Ref<Image> &p_image) {
		if (p_image.is_null() || p_image->is_empty()) {
			*r_error = "its frame cannot be read back from the renderer (none yet, or Godot runs with --headless, whose renderer keeps no texture's pixels)";
			return false;
		}
		return true;
	};
	switch (p_feed->get_datatype()) {
		case CameraFeed::FEED_RGB: {
			const Ref<Image> image = texture_image(id, CameraServer::FEED_RGBA_IMAGE);
			if (!readable(image)) {
				return cv::Mat();
			}
			const Image::Format format = image->get_format();
			return mat_of(image, format == Image::FORMAT_L8 || format == Image::FORMAT_R8 ? 1 : 3);
		}
		case CameraFeed::FEED_YCBCR: { // one texture: YUY2 in two channels, or Y, Cb, Cr in three
			const Ref<Image> image = texture_image(id, CameraServer::FEED_YCBCR_IMAGE);
			if (!readable(image)) {
				return cv::Mat();
			}
			const Image::Format format = image->get_format();
			return format == Image::FORMAT_RG8 || format == Image::FORMAT_LA8 ? rgb_of_ycbcr(ycbcr_of_yuy2(mat_of(image, 2))) : rgb_of_ycbcr(mat_of(image, 3));
		}
		case CameraFeed::FEED_YCBCR_SEP: { // Y full size; Cb, Cr subsampled in a second texture
			const Ref<Image> y_image = texture_image(id, CameraServer::FEED_Y_IMAGE);
			const Ref<Image> cbcr_image = texture_image(id, CameraServer::FEED_CBCR_IMAGE);
			if (!readable(y_image) || !readable(cbcr_image)) {
				return cv::Mat();
			}
			const cv::Mat y = mat_of(y_image, 1);
			cv::Mat cbcr = mat_of(cbcr_image, 2);
			if (y.empty() || cbcr.empty()) {
				*r_error = "its Y and CbCr images have sizes that do not fit together";
				return cv::Mat();
			}
			cv::resize(cbcr, cbcr, y.size(), 0, 0, cv::INTER_LINEAR);
			cv::Mat planes[3] = { y, cv::Mat(), cv::Mat() };
			cv::split(cbcr, planes + 1);
			cv::Mat ycbcr;
			cv::merge(planes, 3, ycbcr);
			return rgb_of_ycbcr(ycbcr);
		}
		case CameraFeed::FEED_EXTERNAL:
			*r_error = "it gives an external GPU texture (an Android OES texture), which RoomProbe cannot read; choose another feed";
			return cv::Mat();
		default:
			*r_error = "it has given no frame yet";
			return cv::Mat();
	}
}

} // namespace roomprobe
