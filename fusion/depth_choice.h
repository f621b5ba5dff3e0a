/// @file depth_choice.h
/// @brief `blend.depth: auto`: which depth a fusion view carries, the TSDF's raycast or the
/// keyframes' own measurements, chosen from the captured frames by leave-one-out. Each held-out
/// keyframe is rendered from the others both ways and compared with its own depth map; the
/// source with the lower depth AbsRel wins. On a sensor whose per-pixel bias a frame shares with
/// its neighbours (real RGB-D cameras) the keyframes' depth reproduces it and wins; where depth
/// noise is zero-mean and independent (the sim) the TSDF averages it away and wins.
#pragma once

#include <cstdint>
#include <string>

namespace p2i::fusion {

class FusionScene;

/// The outcome of one choice; `source` is what the views use.
struct DepthChoice {
  std::string source = "raycast";  ///< "raycast" or "keyframes"
  int frames = 0;                  ///< keyframes held out (0: too few keyframes, raycast kept)
  int64_t pixels = 0;              ///< pixels compared (valid in the frame and both renders)
  double abs_rel_raycast = 0.0;    ///< mean |z - z_frame| / z_frame over those pixels
  double abs_rel_keyframes = 0.0;
  /// One line for logs: "depth auto: keyframes (leave-one-out AbsRel on 16 keyframes: ...)".
  std::string Describe() const;
};

/// Holds out up to `max_frames` keyframes spread evenly over the scene's keyframes (at least 3
/// keyframes are needed; fewer keep the raycast), renders each at its own pose from the others
/// (CandidateRequest::exclude_keyframe; its frame stays in the TSDF) through the frame camera
/// scaled to at most `max_width` pixels wide, once per depth source, and compares both with the
/// frame's depth (nearest-resized). Ties keep the raycast. Throws std::invalid_argument on
/// max_frames < 1 or max_width < 8.
DepthChoice ChooseDepthSource(FusionScene& scene, int max_frames = 16, int max_width = 160);

}  // namespace p2i::fusion
