// HDR fisheye frames and ground-truth cubemap faces (OpenEXR; recording_io::read_exr_size and
// read_exr_rgb): any bytes give a linear RGB float image of the size the header says, or an error
// naming the file; OpenEXR's exceptions never leave the reader.
#include "fuzz_common.h"

#include <recording/recording_io.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "frame.exr";
	fuzz::write_bytes(path, p_data, p_size);
	int width = 0, height = 0;
	const std::string size_error = recording_io::read_exr_size(path.string(), &width, &height);
	cv::Mat rgb;
	const std::string error = recording_io::read_exr_rgb(path.string(), &rgb);
	if (!error.empty()) {
		fuzz::require(error.find(path.string()) != std::string::npos, "an EXR error names the file:", error);
		return 0;
	}
	fuzz::require(size_error.empty(), "an EXR that reads has a readable size:", size_error);
	fuzz::require(rgb.type() == CV_32FC3 && rgb.cols == width && rgb.rows == height, "the image has the header's size and is RGB float");
	return 0;
}
