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

/// A synthesized view: rgb CV_8UC3 (RGB order), depth CV_32FC1 metres with 0 = invalid,
/// at the method's output resolution described by `camera`.
using View = scene::RgbdSample;

/// P2I-NET, the CNN baseline, nearest keyframe, depth warp... all behind one interface.
/// Implementations are not thread-safe unless they say so: one caller at a time.
class ViewSynthesizer {
 public:
  virtual ~ViewSynthesizer() = default;

  virtual std::string Name() const = 0;
  /// Calibration of the views it returns (resolution and intrinsics).
  virtual scene::CameraInfo Camera() const = 0;

  virtual View Render(const scene::Pose& pose) = 0;
  /// Default: one Render per pose. Learned methods override with a real batch.
  virtual std::vector<View> RenderBatch(const std::vector<scene::Pose>& poses) {
    std::vector<View> out;
    out.reserve(poses.size());
    for (const auto& p : poses) out.push_back(Render(p));
    return out;
  }

  /// Parameter count and multiply-accumulate FLOPs per view (2 * MACs), 0 for non-learned.
  virtual int64_t ParameterCount() const { return 0; }
  virtual double FlopsPerView() const { return 0.0; }
};

}  // namespace p2i::model
