#pragma once
// OpenCV's headers for the synthetic rig. pkg-config names /usr/include/opencv4 with -I, not
// -isystem, so g++ in C++20 warns about OpenCV's own enum arithmetic
// (-Wdeprecated-enum-enum-conversion) in every file that includes it: silence exactly that one,
// for OpenCV's lines only (as camera/opencv_headers.h does). Include this before any header that
// includes OpenCV, so that theirs are already included.

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop
