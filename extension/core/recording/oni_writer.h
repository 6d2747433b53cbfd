#pragma once
// Writes OpenNI 2 .oni recordings, uncompressed, the way OpenNI2's own Recorder lays them out
// (OpenNI2's OniDataRecords.h): a file header; per stream a "node added" record and its video
// mode properties; "ready" and "data begin" records; then the frames. OpenNI2's OniFile driver
// plays them as if from a depth camera, so a RoomProbe recording or a synthetic scene can feed
// the live RGB-D path (drivers/capture) without hardware. No OpenNI needed to write one.
//
// Built in memory and written by save(): meant for test fixtures and short clips.

#include "recording_reader.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace roomprobe {

class OniWriter {
public:
	enum Node : uint32_t {
		DEPTH = 1,
		COLOR = 2,
	};
	// OpenNI's pixel format numbers.
	static constexpr int DEPTH_1_MM = 100;
	static constexpr int DEPTH_100_UM = 101;
	static constexpr int RGB888 = 200;

	// Declares a stream of p_frames frames (all streams before begin_data()).
	void add_stream(Node p_node, int p_width, int p_height, int p_oni_format, int p_frames);
	// After the streams, before the frames: OpenNI reads the header records up to the first "data begin".
	void begin_data();
	// One frame's pixels: 16-bit depth or 8-bit R, G, B, row by row; frame ids count from 1.
	void add_frame(Node p_node, uint64_t p_timestamp_us, uint32_t p_frame_id, const std::string &p_pixels);
	// Writes the file, replacing p_path whole or leaving it as it was (io/replace_file.h); an empty
	// string, or the error naming it.
	std::string save(const std::string &p_path);

	template <class T>
	static std::string raw(const std::vector<T> &p_values) {
		return std::string(reinterpret_cast<const char *>(p_values.data()), p_values.size() * sizeof(T));
	}

private:
	enum Record : uint32_t {
		INT_PROPERTY = 0x03,
		GENERAL_PROPERTY = 0x06,
		NODE_DATA_BEGIN = 0x08,
		NODE_STATE_READY = 0x09,
		NEW_DATA = 0x0A,
		END = 0x0B,
		NODE_ADDED = 0x0D,
	};
	void record(Record p_type, uint32_t p_node, const std::string &p_fields, const std::string &p_payload = "", uint64_t p_undo = 0);
	void general_property(uint32_t p_node, const std::string &p_name, const std::string &p_data);
	void int_property(uint32_t p_node, const std::string &p_name, uint64_t p_value);

	std::string bytes; // the records, after the file header
	std::map<uint32_t, uint32_t> frame_counts;
	std::map<uint32_t, uint64_t> last_frame_position;
	uint64_t max_timestamp_us = 0;
};

// Writes the RGB-D stream of p_recording (frames p_first to p_first + p_count, all when p_count
// is 0) as an .oni file: depth in millimetres and RGB888 at the rig's RGB size, timestamps from
// the recording's. An empty string, or the error naming the frame or file.
std::string write_oni_from_recording(const RecordingReader &p_recording, const std::string &p_path, size_t p_first = 0, size_t p_count = 0);

} // namespace roomprobe
