#pragma once
// How a cubemap's pixels map to directions, and the one-file layout recordings store cubemaps in
// (docs/recording-format.md, "Cubemaps").
//
// Faces follow the OpenGL cubemap convention, which Godot (Vulkan) shares: face order +X, -X,
// +Y, -Y, +Z, -Z; world axes, Y up, right-handed; a face's row 0 is the top row of its image.
// For face pixel (u, v) of an N x N face, (0, 0) the centre of the top-left pixel, let
// s = 2 (u + 0.5) / N - 1 and t = 2 (v + 0.5) / N - 1, both in (-1, 1). The direction is:
//
//   +X: ( 1, -t, -s)      -X: (-1, -t,  s)
//   +Y: ( s,  1,  t)      -Y: ( s, -1, -t)
//   +Z: ( s, -t,  1)      -Z: (-s, -t, -1)
//
// (the OpenGL specification's table read backwards: +X has sc = -z, tc = -y, and so on).
//
// The file layout is a vertical strip, N wide and 6 N tall, faces top to bottom in the order
// above: face f holds rows [f N, (f + 1) N). It is what Godot's cubemap import calls "1x6".

#include <opencv2/core/mat.hpp>

#include <array>

#include <glm/vec3.hpp>

namespace roomprobe {

// The six faces of a cubemap in the order +X, -X, +Y, -Y, +Z, -Z (the OpenGL and Godot layer
// order), each square, all the same size. See below for how pixels map to directions.
using CubemapFaces = std::array<cv::Mat, 6>;

enum CubemapFace {
	CUBEMAP_POSITIVE_X = 0,
	CUBEMAP_NEGATIVE_X = 1,
	CUBEMAP_POSITIVE_Y = 2,
	CUBEMAP_NEGATIVE_Y = 3,
	CUBEMAP_POSITIVE_Z = 4,
	CUBEMAP_NEGATIVE_Z = 5,
};

// "+X", "-X", ... for messages.
const char *cubemap_face_name(int p_face);

// The direction through face pixel (p_u, p_v) of a p_size x p_size face (the table above),
// normalised. Pixel coordinates may be fractional: (0, 0) is the centre of the top-left pixel,
// (-0.5, -0.5) its top-left corner.
glm::dvec3 cubemap_direction(int p_face, double p_u, double p_v, int p_size);

// The inverse: the face a (non-zero) direction falls on, and its pixel coordinates there, same
// convention as cubemap_direction. Ties between faces go to X, then Y, then Z.
void cubemap_face_pixel(const glm::dvec3 &p_direction, int p_size, int *r_face, double *r_u, double *r_v);

// Stacks six N x N faces of one type into the N x 6N strip. Returns an empty Mat when the faces
// are empty, not square, or not all the same size and type.
cv::Mat cubemap_faces_to_strip(const CubemapFaces &p_faces);
// Splits an N x 6N strip into its faces (each a copy). Returns all-empty faces when the strip is
// not N x 6N.
CubemapFaces cubemap_strip_to_faces(const cv::Mat &p_strip);

} // namespace roomprobe
