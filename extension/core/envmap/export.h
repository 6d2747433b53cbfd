#pragma once
// Writing environment maps for tools and people.
//
// - EXR: the recordings' cubemap file layout (types/cubemap_layout.h): an N x 6N vertical
//   strip, faces top to bottom +X -X +Y -Y +Z -Z, channels R, G, B as 32-bit float (so a write
//   and read round trip is exact), ZIP compressed.
// - PNG "net": a horizontal cross, 4N wide and 3N tall, for looking at:
//       .   +Y   .   .
//       -X  +Z  +X  -Z
//       .   -Y   .   .
//   which folds into the cube with the convention's face orientations (+Y's bottom edge meets
//   +Z's top edge, +Z's right edge meets +X's left edge, and so on); empty cells are black.
//   Tone mapping: each linear channel is clamped to [0, 1] (1.0 is the fisheye's white, see
//   coarse_texture.h), encoded with the sRGB transfer function and scaled to 0..255, rounded.
//
// Nothing here throws: the functions return "" on success, else an error naming the file. A file
// written replaces its path whole or leaves it as it was (io/replace_file.h).

#include "cubemap.h"

#include <cstdint>
#include <string>

namespace roomprobe {

std::string write_cubemap_exr(const std::string &p_path, const Cubemap &p_cubemap);
// Reads an N x 6N strip EXR (R, G, B channels, any pixel type) into r_cubemap.
std::string read_cubemap_exr(const std::string &p_path, Cubemap *r_cubemap);

// The 8-bit horizontal cross above, CV_8UC3 in R, G, B order (empty for an invalid cubemap).
cv::Mat cubemap_net_image(const Cubemap &p_cubemap);
// The cell (column, row) of face p_face in the cross, in units of N.
void cubemap_net_cell(int p_face, int *r_column, int *r_row);
std::string write_cubemap_png_net(const std::string &p_path, const Cubemap &p_cubemap);

// The tone map above for one linear value: 0..255.
uint8_t tone_map_srgb8(float p_linear);

} // namespace roomprobe
