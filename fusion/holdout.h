/// @file holdout.h
/// @brief The keyframes a fusion scene holds out to check its own options by leave-one-out
/// (depth_choice.h, align_choice.h): which ones, and the small camera they are rendered through.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "scene/camera_info.h"

namespace p2i::fusion {

class FusionScene;

struct Holdouts {
  /// The frame camera scaled to at most the asked width (its aspect kept), or the frame camera.
  scene::CameraInfo camera;
  /// Keyframe indices spread evenly over the scene's keyframes, in order; empty when the scene
  /// has fewer than 3 keyframes (too few to leave one out and still blend).
  std::vector<int> indices;
};

/// Up to `max_frames` keyframes of `scene` spread evenly over its capture, and its frame camera
/// scaled to at most `max_width` pixels wide. Throws std::invalid_argument naming `who` on
/// max_frames < 1 or max_width < 8.
Holdouts PickHoldouts(const FusionScene& scene, int max_frames, int max_width, const char* who);

/// `image` resized to `camera`'s size with `interpolation` (cv::INTER_*), or itself (no copy)
/// when it already has that size.
cv::Mat ResizedTo(const cv::Mat& image, const scene::CameraInfo& camera, int interpolation);

}  // namespace p2i::fusion
