/// @file submap_choice.cc
/// @brief The leave-one-out choice between a fusion view's submaps and its global TSDF
/// (submap_choice.h).
#include "fusion/submap_choice.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "fusion/fusion_scene.h"
#include "fusion/holdout.h"

namespace p2i::fusion {

std::string SubmapChoice::Describe() const {
  if (frames == 0) return "submaps auto: global (fewer than 3 keyframes or 2 submaps)";
  char buf[260];
  const double db = mse_submaps > 0.0 && mse_global > 0.0 ? 10.0 * std::log10(mse_global / mse_submaps) : 0.0;
  std::snprintf(buf, sizeof(buf),
                "submaps auto: %s (%d submaps; leave-one-out colour MSE on %d keyframes, %lld pixels: "
                "global %.3g, submaps %.3g, %+.2f dB; needs %.0f %% less)",
                used ? "used" : "global", submaps, frames, static_cast<long long>(pixels), mse_global,
                mse_submaps, db, 100.0 * min_gain);
  return buf;
}

SubmapChoice ChooseSubmaps(FusionScene& scene, int max_frames, int max_width, double min_gain) {
  if (!(min_gain >= 0.0 && min_gain < 1.0))
    throw std::invalid_argument("ChooseSubmaps: min_gain must be in [0, 1)");
  const Holdouts held = PickHoldouts(scene, max_frames, max_width, "ChooseSubmaps");
  SubmapChoice out;
  out.min_gain = min_gain;
  out.submaps = scene.submaps() ? static_cast<int>(scene.submaps()->size()) : 0;
  if (held.indices.empty() || out.submaps < 2) return out;
  CandidateRequest global;  // the surface alone differs: raycast depth, no alignment
  global.slot_planes = false;
  global.align = false;
  global.keyframe_depth = false;
  global.submaps = false;
  CandidateRequest local = global;
  local.submaps = true;
  const PairedColourError err = CompareHeldOutColour(scene, held, global, local);
  out.frames = static_cast<int>(held.indices.size());
  out.pixels = err.n;
  if (err.n == 0) return out;
  out.mse_global = err.mse_a();
  out.mse_submaps = err.mse_b();
  out.used = out.mse_submaps < (1.0 - min_gain) * out.mse_global;
  return out;
}

}  // namespace p2i::fusion
