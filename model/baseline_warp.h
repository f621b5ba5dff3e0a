/// @file baseline_warp.h
/// @brief Depth-image-based rendering (DIBR) baseline: forward-warps the k nearest training RGB-D
/// frames into the requested pose, z-buffers, blends, marks holes, optionally fills them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/view_synthesizer.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::model {

struct DepthWarpOptions {
  int k = 4;                        ///< number of nearest training frames warped per view
  double metres_per_degree = 0.01;  ///< rotation weight of the pose distance (coverage.h)
  /// Relative depth tolerance of the blend: at each pixel, samples (from any source frame) whose
  /// depth is within z_tolerance * z_front of the front-most sample are blended, the rest are
  /// occluded.
  double z_tolerance = 0.05;
  /// Fill holes (pixels no source reaches) by push-pull (pyramid average of valid pixels) for RGB
  /// and depth.
  /// Off: holes stay marked as rgb (0, 0, 0) and depth 0.
  bool fill_holes = false;
  /// Reads the keys present in a YAML map (others keep their defaults), then Validate().
  /// Unknown keys and bad values throw std::runtime_error naming `source`, the line and the key.
  static DepthWarpOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// Forward warping of RGB-D keyframes (the classic DIBR baseline).
///
/// For a requested pose P_t: pick the k training frames closest by CombinedPoseDistance; for each
/// source frame s, every pixel (u, v) with depth z > 0 (z-depth along the optical axis, metres) is
/// back-projected with the dataset intrinsics, X = P_t^-1 * P_s * z K_s^-1 (u, v, 1), projected
/// with the output intrinsics to the nearest pixel, and kept when it is the nearest sample of that
/// source there (per-source z-buffer). Sources are then blended per pixel: samples within the
/// z tolerance of the front-most one are averaged with weights 1 / (d_pose(s) + 1e-3), so a
/// source close to the requested pose dominates. No splatting: magnification leaves one-pixel
/// cracks, which are holes (the fill option closes them).
///
/// Output: rgb CV_8UC3 RGB, depth CV_32FC1 at the dataset camera (default) or the CameraInfo
/// given at construction. Render is not thread-safe (ViewSynthesizer contract).
class DepthWarp : public ViewSynthesizer {
 public:
  /// Throws std::invalid_argument when `training` has no frames, a frame lacks rgb or depth of
  /// the dataset camera's size, or options are invalid.
  DepthWarp(scene::RgbdDataset training, DepthWarpOptions options = {},
            std::optional<scene::CameraInfo> output_camera = std::nullopt);

  std::string Name() const override { return "depth_warp"; }
  scene::CameraInfo Camera() const override { return output_camera_; }
  scene::RgbdSample Render(const scene::Pose& pose) override;

  /// Fraction of output pixels no source reached in the last Render (before any hole fill).
  double LastHoleFraction() const { return last_hole_fraction_; }

 private:
  scene::RgbdDataset training_;
  std::vector<scene::Pose> poses_;
  DepthWarpOptions options_;
  scene::CameraInfo output_camera_;
  double last_hole_fraction_ = 0.0;
};

}  // namespace p2i::model
