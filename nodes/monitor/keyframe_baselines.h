/// @file keyframe_baselines.h
/// @brief The two free baselines the monitor scores beside the served views: nearest keyframe
/// and depth warp, on the same poses, so the demo summary shows what P2I-NET has to beat.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <vector>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

/// Keyframes are the poses of the frames captured so far (from `rgbd`); their images are those
/// poses rendered exactly by the sim scene with the sim camera and centre-cropped/resized to
/// the view's size, i.e. what the camera delivered and the trainer trained on. For a view pose:
///   nearest  = the keyframe closest by |dt| + kMetresPerRadian * angle (model/coverage.h)
///   warp     = model::DepthWarp of the kWarpFrames closest keyframes, holes filled
/// Rendered keyframes are cached for the last view size asked. Not thread-safe.
class KeyframeBaselines {
 public:
  static constexpr double kMetresPerRadian = 0.5;
  static constexpr int kWarpFrames = 4;

  struct Scores {
    double nearest_psnr = 0, nearest_ssim = 0;  ///< RGB, as model::Psnr / model::Ssim
    double warp_psnr = 0, warp_ssim = 0;
  };

  /// `sim` must outlive this object.
  KeyframeBaselines(const scene::SimScene* sim, scene::CameraInfo sim_camera);

  void AddKeyframe(const scene::Pose& pose) { poses_.push_back(pose); }
  size_t Size() const { return poses_.size(); }

  /// Both baselines at `pose`, scored against `truth` (its rgb's size is the view size);
  /// nullopt before the first keyframe.
  std::optional<Scores> Score(const scene::Pose& pose, const scene::RgbdSample& truth);

 private:
  const scene::RgbdSample& Keyframe(size_t i, int w, int h);

  const scene::SimScene* sim_;
  scene::CameraInfo sim_camera_;
  std::vector<scene::Pose> poses_;
  std::map<size_t, scene::RgbdSample> cache_;
  int cache_w_ = 0, cache_h_ = 0;
};

}  // namespace p2i::nodes
