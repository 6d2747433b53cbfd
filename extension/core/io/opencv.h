#pragma once
// OpenCV's headers, for all of extension/core, its tests and tools: include this one rather than
// <opencv2/...>, and before any header that includes OpenCV, so that theirs are already included.
// Not imgcodecs: images are read by io/image_codec.h and io/radiance_hdr.h, so that nothing pulls
// in libopencv_imgcodecs (GDAL, poppler, HDF5, ~170 libraries); tests that compare with it
// include <opencv2/imgcodecs.hpp> themselves.
// OpenCV's headers mix enumeration types in arithmetic, which C++20 deprecates
// (-Wdeprecated-enum-enum-conversion). pkg-config names /usr/include/opencv4 with -I, not
// -isystem (SConstruct's pkg() turns it into -isystem, other builds and tools may not), so g++
// would warn about OpenCV's own lines in every file that includes them. The warnings are
// OpenCV's, not ours: silence exactly that one, for OpenCV's lines only.

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop
