// PNG frames (io/image_codec.h png_decode, recording/recording_io.h check_png_bytes, the check a
// recording's frames get when opened) and raw frames (io/raw_frame.h raw_frame_decode): any bytes
// decode to an image within the limits, or give a reason; a PNG the chunk walk calls complete
// either decodes or is called corrupt.
#include "fuzz_common.h"

#include <io/image_codec.h>
#include <io/raw_frame.h>
#include <recording/recording_io.h>

#include <vector>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	cv::Mat image;
	const std::string error = png_decode(p_data, p_size, &image);
	if (error.empty()) {
		fuzz::require(!image.empty() && int64_t(image.total()) <= kImageMaxPixels, "a decoded PNG is an image within the pixel limit");
	} else {
		fuzz::require(image.empty(), "a PNG that fails to decode gives no image");
	}
	cv::Mat frame;
	const std::string raw = raw_frame_decode(p_data, p_size, &frame);
	fuzz::require(raw.empty() ? !frame.empty() && int64_t(frame.total()) <= kImageMaxPixels && frame.total() * frame.elemSize() <= kRawFrameMaxBytes : frame.empty(),
			"a raw frame decodes to an image within the limits, or gives none:", raw);
	const std::vector<uint8_t> bytes(p_data, p_data + p_size);
	const std::string walk = recording_io::check_png_bytes(bytes);
	fuzz::require(walk.empty() || !walk.empty(), "the chunk walk returns"); // reaching here is the check: no crash, no hang
	return 0;
}
