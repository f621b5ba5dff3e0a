/// @file depth_choice.cc
/// @brief The leave-one-out choice of a fusion view's depth source (depth_choice.h).
#include "fusion/depth_choice.h"

#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "fusion/fusion_scene.h"
#include "fusion/holdout.h"

namespace p2i::fusion {
namespace {

// Sums of |z - truth| / truth over the pixels valid in truth, a and b.
struct PairedError {
  double sum_a = 0.0, sum_b = 0.0;
  int64_t n = 0;
  void Add(const cv::Mat& truth, const cv::Mat& a, const cv::Mat& b) {
    for (int v = 0; v < truth.rows; ++v) {
      const float* t = truth.ptr<float>(v);
      const float* pa = a.ptr<float>(v);
      const float* pb = b.ptr<float>(v);
      for (int u = 0; u < truth.cols; ++u) {
        if (!(t[u] > 0.0f && pa[u] > 0.0f && pb[u] > 0.0f)) continue;
        sum_a += std::fabs(pa[u] - t[u]) / t[u];
        sum_b += std::fabs(pb[u] - t[u]) / t[u];
        ++n;
      }
    }
  }
};

}  // namespace

std::string DepthChoice::Describe() const {
  if (frames == 0) return "depth auto: raycast (fewer than 3 keyframes to hold out)";
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "depth auto: %s (leave-one-out AbsRel on %d keyframes, %lld pixels: raycast %.4f, "
                "keyframes %.4f)",
                source.c_str(), frames, static_cast<long long>(pixels), abs_rel_raycast, abs_rel_keyframes);
  return buf;
}

DepthChoice ChooseDepthSource(FusionScene& scene, int max_frames, int max_width) {
  const Holdouts held = PickHoldouts(scene, max_frames, max_width, "ChooseDepthSource");
  DepthChoice out;
  if (held.indices.empty()) return out;
  PairedError err;
  for (int i : held.indices) {
    const scene::RgbdSample& frame = scene.keyframes()[static_cast<size_t>(i)];
    const cv::Mat truth = ResizedTo(frame.depth, held.camera, cv::INTER_NEAREST);
    CandidateRequest request;
    request.exclude_keyframe = i;
    request.slot_planes = false;
    request.align = false;  // the depth does not depend on it
    request.keyframe_depth = false;
    const ViewCandidates ray = scene.RenderCandidates(frame.pose, held.camera, request);
    request.keyframe_depth = true;
    const ViewCandidates kf = scene.RenderCandidates(frame.pose, held.camera, request);
    err.Add(truth, ray.depth, kf.depth);
  }
  out.frames = static_cast<int>(held.indices.size());
  out.pixels = err.n;
  if (err.n == 0) return out;
  out.abs_rel_raycast = err.sum_a / static_cast<double>(err.n);
  out.abs_rel_keyframes = err.sum_b / static_cast<double>(err.n);
  if (out.abs_rel_keyframes < out.abs_rel_raycast) out.source = "keyframes";
  return out;
}

}  // namespace p2i::fusion
