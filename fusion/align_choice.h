/// @file align_choice.h
/// @brief `blend.align_iterations: auto`: whether a fusion view aligns its keyframe slots before
/// the blend (floating textures, slot_alignment.h), chosen from the captured frames by
/// leave-one-out. Each held-out keyframe is rendered from the others with and without the
/// alignment and compared with its own colour; the alignment is kept when it lowers the colour
/// error by at least a set fraction. Where poses and geometry are off by a pixel or two (real
/// odometry, a real depth sensor) the keyframes' detail lands at different pixels and aligning
/// them pays (+0.7 dB on study-room); where poses are exact (the sim) it changes nothing and
/// costs ~1.7 ms per 128x128 view, so it stays off.
#pragma once

#include <cstdint>
#include <string>

namespace p2i::fusion {

class FusionScene;

/// The outcome of one choice; `aligned` is what the views use.
struct AlignChoice {
  bool aligned = false;
  int frames = 0;            ///< keyframes held out (0: too few keyframes, alignment off)
  int64_t pixels = 0;        ///< pixels compared (observed in both renders)
  double mse_off = 0.0;      ///< mean squared colour error (RGB in [0, 1]) without alignment
  double mse_on = 0.0;       ///< the same with it
  double min_gain = 0.0;     ///< the fraction of mse_off the alignment had to save
  /// One line for logs: "align auto: on (leave-one-out colour error on 16 keyframes, ...)".
  std::string Describe() const;
};

/// Holds out up to `max_frames` keyframes spread evenly over the scene's keyframes (at least 3
/// are needed; fewer keep the alignment off), renders each at its own pose from the others
/// (CandidateRequest::exclude_keyframe) through the frame camera scaled to at most `max_width`
/// pixels wide, once without and once with the scene's alignment rounds (at least one), and
/// compares both with the frame's colour (area-resized) over the pixels both observe. Alignment
/// is chosen when its error is below (1 - min_gain) x the error without it. Throws
/// std::invalid_argument on max_frames < 1, max_width < 8 or min_gain outside [0, 1).
AlignChoice ChooseAlignment(FusionScene& scene, int max_frames = 16, int max_width = 160,
                            double min_gain = 0.02);

}  // namespace p2i::fusion
