#pragma once
// The OpenCV headers the recording code uses. OpenCV's headers mix enumeration types in
// arithmetic, which C++20 deprecates; they are not ours, so that warning is off for them only.

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop
