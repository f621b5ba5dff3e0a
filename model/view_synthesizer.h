/// @file view_synthesizer.h
/// @brief The one interface every synthesis method implements: pose in, RGB-D view out.
/// No LibTorch here: nodes and tools include this header only.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::model {

/// P2I-NET, the CNN baseline, nearest keyframe, depth warp... all behind one interface. A
/// synthesized view is a scene::RgbdSample (the wire form is msgs::View): rgb CV_8UC3 (RGB
/// order), depth CV_32FC1 metres with 0 = invalid, at the resolution of Camera(); its pose is
/// the requested pose.
/// Implementations are not thread-safe unless they say so: one caller at a time.
class ViewSynthesizer {
 public:
  virtual ~ViewSynthesizer() = default;

  virtual std::string Name() const = 0;
  /// Calibration of the views it returns (resolution and intrinsics).
  virtual scene::CameraInfo Camera() const = 0;

  virtual scene::RgbdSample Render(const scene::Pose& pose) = 0;
  /// Default: one Render per pose. Learned methods override with a real batch.
  virtual std::vector<scene::RgbdSample> RenderBatch(const std::vector<scene::Pose>& poses) {
    std::vector<scene::RgbdSample> out;
    out.reserve(poses.size());
    for (const auto& p : poses) out.push_back(Render(p));
    return out;
  }

  /// Parameter count and multiply-accumulate FLOPs per view (2 * MACs), 0 for non-learned.
  virtual int64_t ParameterCount() const { return 0; }
  virtual double FlopsPerView() const { return 0.0; }
};

}  // namespace p2i::model
