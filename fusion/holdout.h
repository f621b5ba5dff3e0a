/// @file holdout.h
/// @brief The keyframes a fusion scene holds out to check its own options by leave-one-out
/// (depth_choice.h, align_choice.h): which ones, and the small camera they are rendered through.
#pragma once

#include <cstdint>
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

struct ViewCandidates;
struct CandidateRequest;

/// Sums of squared colour errors of two renders of one held-out keyframe against its colour
/// (CV_8UC3 RGB, the renders' size), over the pixels both renders observe (RGB in [0, 1]).
struct PairedColourError {
  double sum_a = 0.0, sum_b = 0.0;
  int64_t n = 0;  ///< pixels compared
  void Add(const cv::Mat& truth_rgb8, const ViewCandidates& a, const ViewCandidates& b);
  /// Mean squared error per channel of a and of b (0 when no pixel was compared).
  double mse_a() const { return n > 0 ? sum_a / (3.0 * static_cast<double>(n)) : 0.0; }
  double mse_b() const { return n > 0 ? sum_b / (3.0 * static_cast<double>(n)) : 0.0; }
};

/// Renders each keyframe of `held` at its own pose from the others (`exclude_keyframe` set to
/// it) through `held.camera` twice, with request `a` and with request `b`, and sums both renders'
/// colour errors against the frame's colour (area-resized).
PairedColourError CompareHeldOutColour(FusionScene& scene, const Holdouts& held, CandidateRequest a,
                                       CandidateRequest b);

/// `image` resized to `camera`'s size with `interpolation` (cv::INTER_*), or itself (no copy)
/// when it already has that size.
cv::Mat ResizedTo(const cv::Mat& image, const scene::CameraInfo& camera, int interpolation);

}  // namespace p2i::fusion
