#pragma once
// Core images (cv::Mat) to Godot images and textures. The one place for these conversions.

#include <opencv2/core/mat.hpp>

#include <rp_godot/godot.h>

namespace roomprobe {

// CV_8UC1 -> L8, CV_8UC3 (R, G, B order) -> RGB8, CV_32FC1 -> RF, CV_32FC3 -> RGBF. An
// unsupported type or an empty matrix gives a null Ref.
godot::Ref<godot::Image> image_from_mat(const cv::Mat &p_mat);
// Puts p_image into r_texture, updating it in place when size and format are unchanged
// (no new GPU texture per frame), creating it otherwise.
void show_in_texture(const godot::Ref<godot::Image> &p_image, godot::Ref<godot::ImageTexture> &r_texture);

} // namespace roomprobe
