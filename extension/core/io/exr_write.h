#pragma once
// EXR files written whole or not at all (issue #38): OpenEXR writes into memory, where nothing can
// fail unseen (its file stream drops an error at close, after the last bytes), and the bytes then
// replace the path (io/replace_file.h).

#include <ImfFrameBuffer.h>
#include <ImfHeader.h>

#include <string>

namespace roomprobe {

// p_rows scan lines of p_buffer under p_header as the whole of p_path. "" or the error naming
// p_path; never throws.
std::string write_exr(const std::string &p_path, const Imf::Header &p_header, const Imf::FrameBuffer &p_buffer, int p_rows);

} // namespace roomprobe
