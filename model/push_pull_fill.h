/// @file push_pull_fill.h
/// @brief Push-pull hole filling (Gortler et al. 1996) of a single-channel float image, shared by
/// the depth-warp baseline and the fusion methods.
#pragma once

#include <opencv2/core.hpp>

namespace p2i::model {

/// Averages the valid pixels down a pyramid, then fills each level's holes from the upsampled
/// coarser level. `valid` is CV_8UC1 (non-zero = keep); `image` is CV_32FC1 and is filled in
/// place where `valid` is zero. Single channel: split multi-channel images first.
void PushPullFill(cv::Mat& image, const cv::Mat& valid);

/// PushPullFill of an RGB CV_8UC3 image (per channel) and of a CV_32FC1 depth map where `valid`
/// is zero; nothing happens when every pixel is valid or none is.
void PushPullFillRgbd(cv::Mat& rgb, cv::Mat& depth, const cv::Mat& valid);

}  // namespace p2i::model
