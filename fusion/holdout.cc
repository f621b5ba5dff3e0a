/// @file holdout.cc
/// @brief The held-out keyframes of a fusion scene's leave-one-out checks (holdout.h).
#include "fusion/holdout.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "fusion/fusion_scene.h"

namespace p2i::fusion {

Holdouts PickHoldouts(const FusionScene& scene, int max_frames, int max_width, const char* who) {
  if (max_frames < 1) throw std::invalid_argument(std::string(who) + ": max_frames must be >= 1");
  if (max_width < 8) throw std::invalid_argument(std::string(who) + ": max_width must be >= 8");
  Holdouts out;
  const scene::CameraInfo& full = scene.frame_camera();
  const int w = std::min(full.image_width, max_width);
  const int h = std::max(1, static_cast<int>(std::lround(full.image_height * static_cast<double>(w) /
                                                         full.image_width)));
  out.camera = w == full.image_width ? full : full.Scaled(w, h);
  const int n = static_cast<int>(scene.keyframes().size());
  if (n < 3) return out;
  const int m = std::min(n, max_frames);
  for (int k = 0; k < m; ++k) out.indices.push_back(std::min(n - 1, static_cast<int>((k + 0.5) * n / m)));
  return out;
}

void PairedColourError::Add(const cv::Mat& truth_rgb8, const ViewCandidates& a, const ViewCandidates& b) {
  for (int v = 0; v < truth_rgb8.rows; ++v) {
    const cv::Vec3b* t = truth_rgb8.ptr<cv::Vec3b>(v);
    const cv::Vec3f* pa = a.blended.ptr<cv::Vec3f>(v);
    const cv::Vec3f* pb = b.blended.ptr<cv::Vec3f>(v);
    const uint8_t* oa = a.observed.ptr<uint8_t>(v);
    const uint8_t* ob = b.observed.ptr<uint8_t>(v);
    for (int u = 0; u < truth_rgb8.cols; ++u) {
      if (!(oa[u] && ob[u])) continue;
      for (int ch = 0; ch < 3; ++ch) {
        const double truth = t[u][ch] / 255.0;
        sum_a += (pa[u][ch] - truth) * (pa[u][ch] - truth);
        sum_b += (pb[u][ch] - truth) * (pb[u][ch] - truth);
      }
      ++n;
    }
  }
}

PairedColourError CompareHeldOutColour(FusionScene& scene, const Holdouts& held, CandidateRequest a,
                                       CandidateRequest b) {
  PairedColourError err;
  for (int i : held.indices) {
    const scene::RgbdSample& frame = scene.keyframes()[static_cast<size_t>(i)];
    const cv::Mat truth = ResizedTo(frame.rgb, held.camera, cv::INTER_AREA);
    a.exclude_keyframe = i;
    b.exclude_keyframe = i;
    const ViewCandidates ra = scene.RenderCandidates(frame.pose, held.camera, a);
    const ViewCandidates rb = scene.RenderCandidates(frame.pose, held.camera, b);
    err.Add(truth, ra, rb);
  }
  return err;
}

cv::Mat ResizedTo(const cv::Mat& image, const scene::CameraInfo& camera, int interpolation) {
  if (image.cols == camera.image_width && image.rows == camera.image_height) return image;
  cv::Mat out;
  cv::resize(image, out, cv::Size(camera.image_width, camera.image_height), 0.0, 0.0, interpolation);
  return out;
}

}  // namespace p2i::fusion
