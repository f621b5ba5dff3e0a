/// @file align_choice.cc
/// @brief The leave-one-out choice of a fusion view's slot alignment (align_choice.h).
#include "fusion/align_choice.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "fusion/fusion_scene.h"
#include "fusion/holdout.h"

namespace p2i::fusion {
namespace {

// Sums of squared colour errors against truth over the pixels both renders observe.
struct PairedColourError {
  double sum_a = 0.0, sum_b = 0.0;
  int64_t n = 0;
  void Add(const cv::Mat& truth_rgb8, const ViewCandidates& a, const ViewCandidates& b) {
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
};

}  // namespace

std::string AlignChoice::Describe() const {
  if (frames == 0) return "align auto: off (fewer than 3 keyframes to hold out)";
  char buf[240];
  const double db = mse_on > 0.0 && mse_off > 0.0 ? 10.0 * std::log10(mse_off / mse_on) : 0.0;
  std::snprintf(buf, sizeof(buf),
                "align auto: %s (leave-one-out colour MSE on %d keyframes, %lld pixels: off %.3g, "
                "aligned %.3g, %+.2f dB; needs %.0f %% less)",
                aligned ? "on" : "off", frames, static_cast<long long>(pixels), mse_off, mse_on, db,
                100.0 * min_gain);
  return buf;
}

AlignChoice ChooseAlignment(FusionScene& scene, int max_frames, int max_width, double min_gain) {
  if (!(min_gain >= 0.0 && min_gain < 1.0))
    throw std::invalid_argument("ChooseAlignment: min_gain must be in [0, 1)");
  const Holdouts held = PickHoldouts(scene, max_frames, max_width, "ChooseAlignment");
  AlignChoice out;
  out.min_gain = min_gain;
  if (held.indices.empty()) return out;
  PairedColourError err;
  for (int i : held.indices) {
    const scene::RgbdSample& frame = scene.keyframes()[static_cast<size_t>(i)];
    const cv::Mat truth = ResizedTo(frame.rgb, held.camera, cv::INTER_AREA);
    CandidateRequest request;
    request.exclude_keyframe = i;
    request.slot_planes = false;
    request.align = false;
    const ViewCandidates off = scene.RenderCandidates(frame.pose, held.camera, request);
    request.align = true;
    const ViewCandidates on = scene.RenderCandidates(frame.pose, held.camera, request);
    err.Add(truth, off, on);
  }
  out.frames = static_cast<int>(held.indices.size());
  out.pixels = err.n;
  if (err.n == 0) return out;
  out.mse_off = err.sum_a / (3.0 * static_cast<double>(err.n));
  out.mse_on = err.sum_b / (3.0 * static_cast<double>(err.n));
  out.aligned = out.mse_on < (1.0 - min_gain) * out.mse_off;
  return out;
}

}  // namespace p2i::fusion
