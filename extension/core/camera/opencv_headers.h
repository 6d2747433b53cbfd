#pragma once
// OpenCV's headers, included once for the camera code and its tests. pkg-config names
// /usr/include/opencv4 with -I, not -isystem, so g++ in C++20 warns about OpenCV's own enum
// arithmetic (-Wdeprecated-enum-enum-conversion) in every file that includes it. The warnings are
// OpenCV's, not ours: silence exactly that one, for OpenCV's lines only.

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop
