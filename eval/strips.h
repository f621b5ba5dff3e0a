/// @file strips.h
/// @brief Image strips of the report: ground truth next to every method for the same poses,
/// RGB and depth (colour-mapped), written as PNG.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "scene/rgbd_sample.h"

namespace p2i::eval {

/// Saves one view of a strip: DIR/<k>_rgb.png (8-bit) and DIR/<k>_depth.png (16-bit mm),
/// each atomically. Creates DIR.
void SaveStripView(const std::string& dir, int k, const scene::RgbdSample& view);

/// Depth (CV_32FC1 metres, 0 invalid) to a BGR colour image (turbo map over [0, max_depth_m];
/// invalid pixels black).
cv::Mat ColorMapDepth(const cv::Mat& depth_m, double max_depth_m);

/// Composes the strip of one setting from `strip_dir`/<row>/<k>_{rgb,depth}.png: one row per
/// entry of `rows` (the first is normally "ground_truth"), one column pair (RGB | depth) per
/// view k = 0..views-1, a label at the left. Missing images stay grey. Writes `out_png`
/// (atomically); returns false when no image was found at all.
bool ComposeStrip(const std::string& strip_dir, const std::vector<std::string>& rows, int views,
                  const std::string& out_png);

/// cv::imwrite through a temporary file + rename. `image` in OpenCV's BGR order.
void WritePngAtomic(const std::string& path, const cv::Mat& image);

}  // namespace p2i::eval
