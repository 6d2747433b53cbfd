#include "oni_writer.h"

#include <io/replace_file.h>

#include <cmath>

namespace roomprobe {

namespace {

constexpr uint32_t CODEC_NONE = 'N' | ('O' << 8) | ('N' << 16) | ('E' << 24);
constexpr size_t HEADER_SIZE = 24; // the file header, before the records
constexpr uint32_t RECORD_HEADER_SIZE = 28;

template <class T>
std::string bytes_of(T p_value) {
	return std::string(reinterpret_cast<const char *>(&p_value), sizeof(T));
}
std::string u8(uint8_t p_value) { return bytes_of(p_value); }
std::string u16(uint16_t p_value) { return bytes_of(p_value); }
std::string u32(uint32_t p_value) { return bytes_of(p_value); }
std::string u64(uint64_t p_value) { return bytes_of(p_value); }
std::string name_field(const std::string &p_name) { return u32(uint32_t(p_name.size() + 1)) + p_name + '\0'; }

} // namespace

// "fieldsSize" counts the record header too; the payload follows the fields.
void OniWriter::record(Record p_type, uint32_t p_node, const std::string &p_fields, const std::string &p_payload, uint64_t p_undo) {
	bytes += u32(0x0052494E) + u32(p_type) + u32(p_node) + u32(RECORD_HEADER_SIZE + uint32_t(p_fields.size())) +
			u32(uint32_t(p_payload.size())) + u64(p_undo) + p_fields + p_payload;
}

void OniWriter::general_property(uint32_t p_node, const std::string &p_name, const std::string &p_data) {
	record(GENERAL_PROPERTY, p_node, name_field(p_name) + u32(uint32_t(p_data.size())) + p_data);
}

void OniWriter::int_property(uint32_t p_node, const std::string &p_name, uint64_t p_value) {
	record(INT_PROPERTY, p_node, name_field(p_name) + u32(8) + u64(p_value));
}

void OniWriter::add_stream(Node p_node, int p_width, int p_height, int p_oni_format, int p_frames) {
	const bool depth = p_node == DEPTH;
	const uint32_t bytes_per_pixel = depth ? 2 : 3;
	std::string fields = name_field(depth ? "Depth" : "Image");
	fields += u32(depth ? 2 : 3) + u32(CODEC_NONE) + u32(uint32_t(p_frames)) + u64(0) + u64(UINT64_MAX) + u64(0);
	record(NODE_ADDED, p_node, fields);
	int_property(p_node, "oniRequiredFrameSize", uint64_t(p_width) * uint64_t(p_height) * bytes_per_pixel);
	int_property(p_node, "xnIsGenerating", 1);
	if (depth) {
		int_property(p_node, "xnDeviceMaxDepth", 10000);
	}
	const std::string mode = u32(uint32_t(p_width)) + u32(uint32_t(p_height)) + u32(30);
	int_property(p_node, "xnSupportedMapOutputModesCount", 1);
	general_property(p_node, "xnSupportedMapOutputModes", mode);
	general_property(p_node, "xnMapOutputMode", mode);
	int_property(p_node, "xnPixelFormat", depth ? 4 : 1); // OpenNI 1's grey 16 / RGB24
	int_property(p_node, "oniPixelFormat", uint64_t(p_oni_format));
	// Playback drops every frame of a stream without a cropping state.
	general_property(p_node, "xnCropping", u32(0) + u16(0) + u16(0) + u16(0) + u16(0));
	frame_counts[p_node] = uint32_t(p_frames);
}

void OniWriter::begin_data() {
	for (const auto &[node, frames] : frame_counts) {
		record(NODE_STATE_READY, node, "");
		record(NODE_DATA_BEGIN, node, u32(frames) + u64(UINT64_MAX));
	}
}

void OniWriter::add_frame(Node p_node, uint64_t p_timestamp_us, uint32_t p_frame_id, const std::string &p_pixels) {
	const uint64_t position = bytes.size() + HEADER_SIZE;
	record(NEW_DATA, p_node, u64(p_timestamp_us) + u32(p_frame_id), p_pixels, last_frame_position[p_node]);
	last_frame_position[p_node] = position;
	max_timestamp_us = std::max(max_timestamp_us, p_timestamp_us);
}

std::string OniWriter::save(const std::string &p_path) {
	record(END, 0, "");
	const std::string header = std::string("NI10") + u8(1) + u8(0) + u16(1) + u32(0) + u64(max_timestamp_us) + u32(2);
	bytes.insert(0, header); // save() ends the records: it is the last call
	return replace_file(p_path, bytes.data(), bytes.size()); // whole or not at all: no half .oni left
}

std::string write_oni_from_recording(const RecordingReader &p_recording, const std::string &p_path, size_t p_first, size_t p_count) {
	const size_t total = p_recording.rgbd_count();
	if (p_first >= total) {
		return p_path + ": the recording has " + std::to_string(total) + " RGB-D frames; none from frame " + std::to_string(p_first);
	}
	const size_t count = p_count == 0 ? total - p_first : std::min(p_count, total - p_first);
	const PinholeParams &rgb = p_recording.get_rig().rgb;
	OniWriter writer;
	writer.add_stream(OniWriter::DEPTH, rgb.width, rgb.height, OniWriter::DEPTH_1_MM, int(count));
	writer.add_stream(OniWriter::COLOR, rgb.width, rgb.height, OniWriter::RGB888, int(count));
	writer.begin_data();
	double first_s = 0.0;
	for (size_t i = 0; i < count; i++) {
		const RgbdFrameResult frame = p_recording.read_rgbd(p_first + i);
		if (!frame.ok) {
			return p_path + ": " + frame.error;
		}
		if (i == 0) {
			first_s = frame.frame.timestamp_s;
		}
		// OpenNI counts microseconds from the start; 0 is taken as "no frame", so start at 1 ms.
		const uint64_t timestamp_us = 1000 + uint64_t(std::llround((frame.frame.timestamp_s - first_s) * 1e6));
		std::vector<uint16_t> depth_mm(size_t(rgb.width) * size_t(rgb.height));
		for (int y = 0; y < rgb.height; y++) {
			const float *row = frame.frame.depth_m.ptr<float>(y);
			for (int x = 0; x < rgb.width; x++) {
				const float m = row[x];
				depth_mm[size_t(y) * size_t(rgb.width) + size_t(x)] = std::isfinite(m) && m > 0.0f && m < 65.0f ? uint16_t(std::lround(m * 1000.0f)) : 0;
			}
		}
		const cv::Mat rgb8 = frame.frame.rgb.isContinuous() ? frame.frame.rgb : frame.frame.rgb.clone();
		writer.add_frame(OniWriter::DEPTH, timestamp_us, uint32_t(i + 1), OniWriter::raw(depth_mm));
		writer.add_frame(OniWriter::COLOR, timestamp_us, uint32_t(i + 1), std::string(reinterpret_cast<const char *>(rgb8.data), rgb8.total() * 3));
	}
	return writer.save(p_path);
}

} // namespace roomprobe
