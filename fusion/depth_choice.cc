/// @file depth_choice.cc
/// @brief The leave-one-out choice of a fusion view's depth source (depth_choice.h).
#include "fusion/depth_choice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "fusion/fusion_scene.h"

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
  if (max_frames < 1) throw std::invalid_argument("ChooseDepthSource: max_frames must be >= 1");
  if (max_width < 8) throw std::invalid_argument("ChooseDepthSource: max_width must be >= 8");
  DepthChoice out;
  const auto& keyframes = scene.keyframes();
  const int n = static_cast<int>(keyframes.size());
  if (n < 3) return out;
  const scene::CameraInfo& full = scene.frame_camera();
  const int w = std::min(full.image_width, max_width);
  const int h = std::max(1, static_cast<int>(std::lround(full.image_height * static_cast<double>(w) /
                                                         full.image_width)));
  const scene::CameraInfo camera = w == full.image_width ? full : full.Scaled(w, h);
  const int m = std::min(n, max_frames);
  PairedError err;
  for (int k = 0; k < m; ++k) {
    const int i = std::min(n - 1, static_cast<int>((k + 0.5) * n / m));
    const scene::RgbdSample& frame = keyframes[static_cast<size_t>(i)];
    cv::Mat truth;
    if (w == full.image_width)
      truth = frame.depth;
    else
      cv::resize(frame.depth, truth, cv::Size(w, h), 0.0, 0.0, cv::INTER_NEAREST);
    CandidateRequest request;
    request.exclude_keyframe = i;
    request.slot_planes = false;
    request.keyframe_depth = false;
    const ViewCandidates ray = scene.RenderCandidates(frame.pose, camera, request);
    request.keyframe_depth = true;
    const ViewCandidates kf = scene.RenderCandidates(frame.pose, camera, request);
    err.Add(truth, ray.depth, kf.depth);
  }
  out.frames = m;
  out.pixels = err.n;
  if (err.n == 0) return out;
  out.abs_rel_raycast = err.sum_a / static_cast<double>(err.n);
  out.abs_rel_keyframes = err.sum_b / static_cast<double>(err.n);
  if (out.abs_rel_keyframes < out.abs_rel_raycast) out.source = "keyframes";
  return out;
}

}  // namespace p2i::fusion
