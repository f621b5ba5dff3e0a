/// @file keyframe_baselines.cc
/// @brief KeyframeBaselines (see keyframe_baselines.h).
#include "nodes/monitor/keyframe_baselines.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "model/baseline_warp.h"
#include "model/coverage.h"
#include "model/metrics.h"
#include "scene/image_ops.h"

namespace p2i::nodes {

KeyframeBaselines::KeyframeBaselines(const scene::SimScene* sim, scene::CameraInfo sim_camera)
    : sim_(sim), sim_camera_(std::move(sim_camera)) {}

const scene::RgbdSample& KeyframeBaselines::Keyframe(size_t i, int w, int h) {
  if (w != cache_w_ || h != cache_h_) {
    cache_.clear();
    cache_w_ = w;
    cache_h_ = h;
  }
  auto it = cache_.find(i);
  if (it == cache_.end()) {
    scene::RgbdSample s = sim_->Render(poses_[i], sim_camera_);
    s.pose = poses_[i];
    s.id = "keyframe_" + std::to_string(i);
    it = cache_.emplace(i, scene::CenterCropResizeSample(s, w, h)).first;
  }
  return it->second;
}

std::optional<KeyframeBaselines::Scores> KeyframeBaselines::Score(const scene::Pose& pose,
                                                                  const scene::RgbdSample& truth) {
  if (poses_.empty()) return std::nullopt;
  const double metres_per_degree = kMetresPerRadian * M_PI / 180.0;
  std::vector<std::pair<double, size_t>> by_distance;
  by_distance.reserve(poses_.size());
  for (size_t i = 0; i < poses_.size(); ++i)
    by_distance.push_back({model::CombinedPoseDistance(pose, poses_[i], metres_per_degree), i});
  const size_t k = std::min<size_t>(kWarpFrames, by_distance.size());
  std::partial_sort(by_distance.begin(), by_distance.begin() + k, by_distance.end());
  const int w = truth.rgb.cols, h = truth.rgb.rows;
  Scores s;
  const scene::RgbdSample& nearest = Keyframe(by_distance[0].second, w, h);
  s.nearest_psnr = model::Psnr(nearest.rgb, truth.rgb);
  s.nearest_ssim = model::Ssim(nearest.rgb, truth.rgb);
  scene::RgbdDataset sources;
  sources.camera = scene::CenterCropResizeCamera(sim_camera_, w, h);
  for (size_t j = 0; j < k; ++j) sources.frames.push_back(Keyframe(by_distance[j].second, w, h));
  model::DepthWarpOptions o;
  o.k = static_cast<int>(k);
  o.metres_per_degree = metres_per_degree;
  o.fill_holes = true;
  model::DepthWarp warp(std::move(sources), o);
  const cv::Mat warped = warp.Render(pose).rgb;
  s.warp_psnr = model::Psnr(warped, truth.rgb);
  s.warp_ssim = model::Ssim(warped, truth.rgb);
  return s;
}

}  // namespace p2i::nodes
