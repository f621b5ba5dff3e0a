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

/// What a method with scene geometry (`fusion`) knows of how well one rendered view is observed:
/// the fused surface behind its pixels and the keyframes that coloured them (issue 12 point 4;
/// fusion::ViewCoverage in full). Travels with served views as ViewMeta.observed_fraction and
/// keyframe_angle_deg.
struct ViewGeometry {
  double observed_fraction = 0.0;   ///< pixels whose surface the geometry observed / all pixels
  /// Mean over the keyframe-coloured pixels of the angle (degrees) between the requested ray and
  /// the nearest keyframe ray that sees the point: 0 on a keyframe's pose, grows off the path.
  double keyframe_angle_deg = 0.0;
};

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

  /// The geometry of each view of the last Render or RenderBatch call, in order; empty for
  /// methods without scene geometry (the default).
  virtual std::vector<ViewGeometry> LastGeometry() const { return {}; }

  /// Parameter count and multiply-accumulate FLOPs per view (2 * MACs), 0 for non-learned.
  virtual int64_t ParameterCount() const { return 0; }
  virtual double FlopsPerView() const { return 0.0; }
};

}  // namespace p2i::model
