/// @file baseline_nearest.h
/// @brief Nearest-keyframe baseline: answers a pose with the training frame whose pose is closest.
#pragma once

#include <string>
#include <vector>

#include "model/view_synthesizer.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::model {

struct NearestKeyframeOptions {
  /// Rotation weight of the pose distance |dt| + metres_per_degree * angle_deg (see coverage.h).
  double metres_per_degree = 0.01;
  /// Reads the keys present in a YAML map (others keep their defaults), then Validate().
  /// Unknown keys and bad values throw std::runtime_error naming `source`, the line and the key.
  static NearestKeyframeOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument when metres_per_degree is negative or not finite.
  void Validate() const;
};

/// The simplest "renderer": no synthesis, just the recorded frame from the closest training pose
/// (CombinedPoseDistance). The returned view is a deep copy of that frame's rgb and depth at the
/// dataset camera's resolution, with `pose` set to the requested pose, `stamp` to the frame's and
/// `id` to "nearest:<frame id>". Search is brute force, O(n) per query (a few thousand frames
/// take microseconds; a k-d tree would not pay off for a 6-DoF mixed metric at this size).
/// Not thread-safe for Render (ViewSynthesizer contract); NearestIndex is const and safe.
class NearestKeyframe : public ViewSynthesizer {
 public:
  /// Throws std::invalid_argument when `training` has no frames or options are invalid.
  explicit NearestKeyframe(scene::RgbdDataset training, NearestKeyframeOptions options = {});

  std::string Name() const override { return "nearest_keyframe"; }
  scene::CameraInfo Camera() const override { return training_.camera; }
  scene::RgbdSample Render(const scene::Pose& pose) override;

  /// Index into the training frames of the closest pose (ties: the lower index).
  size_t NearestIndex(const scene::Pose& pose) const;

 private:
  scene::RgbdDataset training_;
  std::vector<scene::Pose> poses_;
  NearestKeyframeOptions options_;
};

}  // namespace p2i::model
