// 16-bit depth frames, PNG or raw, as a recording reads them (recording_io::decode_frame_file, then
// depth_metres_from_raw at the rig's scale): every pixel is no reading (NaN) or a distance in
// (0, 65534 x scale] metres, never 65.535 m nor a negative or infinite one.
#include "fuzz_common.h"

#include <recording/recording_io.h>
#include <recording/recording_types.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "depth.png";
	fuzz::write_bytes(path, p_data, p_size);
	cv::Mat raw;
	const std::string error = recording_io::decode_frame_file(path.string(), &raw, nullptr);
	if (!error.empty()) {
		fuzz::require(error.find(path.string()) != std::string::npos, "a depth frame error names the file:", error);
		return 0;
	}
	if (raw.type() != CV_16UC1) {
		return 0; // the reader calls this an issue, naming the format
	}
	constexpr double SCALE_M = 0.001;
	const cv::Mat depth = depth_metres_from_raw(raw, SCALE_M);
	fuzz::require(depth.type() == CV_32FC1 && depth.size() == raw.size(), "depth in metres has the raw image's size");
	for (int y = 0; y < depth.rows; y++) {
		const float *row = depth.ptr<float>(y);
		const uint16_t *units = raw.ptr<uint16_t>(y);
		for (int x = 0; x < depth.cols; x++) {
			if (units[x] == 0 || units[x] == 65535) {
				fuzz::require(std::isnan(row[x]), "0 and 65535 are no reading");
			} else {
				fuzz::require(row[x] > 0.0f && row[x] <= float(65534 * SCALE_M) + 1e-3f, "a reading is a positive distance");
			}
		}
	}
	return 0;
}
