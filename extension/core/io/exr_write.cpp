#include "exr_write.h"

#include "replace_file.h"

#include <ImfIO.h>
#include <ImfOutputFile.h>

#include <cstring>
#include <exception>

namespace roomprobe {

namespace {

// OpenEXR's output stream into a string: OutputFile seeks back to write its offsets.
class MemoryStream : public Imf::OStream {
public:
	explicit MemoryStream(const std::string &p_name) :
			Imf::OStream(p_name.c_str()) {}

	void write(const char p_bytes[], int p_count) override {
		const size_t end = size_t(position) + size_t(p_count);
		if (bytes.size() < end) {
			bytes.resize(end);
		}
		std::memcpy(bytes.data() + position, p_bytes, size_t(p_count));
		position = end;
	}
	uint64_t tellp() override { return position; }
	void seekp(uint64_t p_position) override { position = p_position; }

	std::string bytes;

private:
	uint64_t position = 0;
};

} // namespace

std::string write_exr(const std::string &p_path, const Imf::Header &p_header, const Imf::FrameBuffer &p_buffer, int p_rows) {
	MemoryStream stream(p_path);
	try {
		Imf::OutputFile file(stream, p_header); // destroyed before the bytes are used: it writes the offsets last
		file.setFrameBuffer(p_buffer);
		file.writePixels(p_rows);
	} catch (const std::exception &e) {
		return p_path + ": " + e.what();
	}
	return replace_file(p_path, stream.bytes.data(), stream.bytes.size());
}

} // namespace roomprobe
