/// @file align_choice.cc
/// @brief The leave-one-out choice of a fusion view's slot alignment (align_choice.h).
#include "fusion/align_choice.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "fusion/fusion_scene.h"
#include "fusion/holdout.h"

namespace p2i::fusion {
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
  CandidateRequest off;
  off.slot_planes = false;
  off.align = false;
  CandidateRequest on = off;
  on.align = true;
  const PairedColourError err = CompareHeldOutColour(scene, held, off, on);
  out.frames = static_cast<int>(held.indices.size());
  out.pixels = err.n;
  if (err.n == 0) return out;
  out.mse_off = err.mse_a();
  out.mse_on = err.mse_b();
  out.aligned = out.mse_on < (1.0 - min_gain) * out.mse_off;
  return out;
}

}  // namespace p2i::fusion
