/// @file submap_choice.h
/// @brief `submaps: {use: auto}`: whether a fusion view's surface comes from the local submaps
/// (submaps.h) or from the global TSDF alone, chosen from the captured frames by leave-one-out.
/// Each held-out keyframe is rendered from the others over both surfaces and compared with its
/// own colour; the submaps are used when they lower the colour error by at least a set fraction.
/// Where two captures' poses disagree where they overlap (real odometry), one global TSDF
/// averages surfaces that are off by centimetres and the keyframes colour the wrong place; where
/// poses are exact (the sim), the global TSDF averages more frames' noise away and wins.
#pragma once

#include <cstdint>
#include <string>

namespace p2i::fusion {

class FusionScene;

/// The outcome of one choice; `used` is what the views use.
struct SubmapChoice {
  bool used = false;
  int frames = 0;          ///< keyframes held out (0: too few keyframes or submaps; global kept)
  int submaps = 0;         ///< submaps the scene had
  int64_t pixels = 0;      ///< pixels compared (observed in both renders)
  double mse_global = 0.0; ///< mean squared colour error (RGB in [0, 1]) over the global TSDF
  double mse_submaps = 0.0;  ///< the same over the submaps
  double min_gain = 0.0;   ///< the fraction of mse_global the submaps had to save
  /// One line for logs: "submaps auto: used (leave-one-out colour MSE on 16 keyframes, ...)".
  std::string Describe() const;
};

/// Holds out up to `max_frames` keyframes spread evenly over the scene's keyframes (at least 3
/// are needed, and at least 2 submaps: a single submap is the global TSDF's frames), renders
/// each at its own pose from the others (CandidateRequest::exclude_keyframe; its frame stays in
/// the TSDFs) through the frame camera scaled to at most `max_width` pixels wide, once over the
/// global TSDF and once over the submaps (raycast depth, no alignment), and compares both with
/// the frame's colour (area-resized) over the pixels both observe. The submaps are chosen when
/// their error is below (1 - min_gain) x the global one's. Throws std::invalid_argument on
/// max_frames < 1, max_width < 8 or min_gain outside [0, 1).
SubmapChoice ChooseSubmaps(FusionScene& scene, int max_frames = 16, int max_width = 160,
                           double min_gain = 0.03);

}  // namespace p2i::fusion
