/// @file slot_alignment.h
/// @brief Floating textures in their cheapest form (Eisemann et al., "Floating Textures",
/// Eurographics 2008): each keyframe slot's colour map is moved by the optical flow from the
/// blend to it, so that the slots' detail lines up before it is blended again. Pose and depth
/// error put the same edge at slightly different pixels in each slot; blended as they are, the
/// view shows the edge doubled or smeared.
#pragma once

#include <string>

#include "fusion/view_candidates.h"

namespace p2i::fusion {

struct SlotAlignmentOptions {
  /// Align-and-blend rounds (0 = off): each round aligns every slot to the previous round's blend.
  int iterations = 0;
  /// `align_iterations: auto` (align_choice.h): `iterations` rounds (1) where a leave-one-out on
  /// the keyframes shows they pay, none elsewhere; chosen at every FusionScene::Prepare.
  bool automatic = false;
  /// Flow vectors longer than this (pixels of the view) are shortened to it: slots further off
  /// than that disagree about the surface, not about its detail.
  double max_shift_px = 3.0;
  /// The DIS preset: "ultrafast" (the default), "fast" or "medium". On study-room the slower
  /// presets gained at most 0.04 dB for 2-5x the flow's time (docs/RESULTS.md "Floating textures").
  std::string flow_preset = "ultrafast";
};

/// `align_iterations: auto`: one round where the leave-one-out shows it pays (BlendOptions' default).
inline SlotAlignmentOptions AutoAlignment() {
  SlotAlignmentOptions o;
  o.iterations = 1;
  o.automatic = true;
  return o;
}

/// Aligns the slots of `c` to its blend and blends them again (`c->blended` and `c->colours`
/// change; weights, depth and the far field do not). Needs the slot planes
/// (CandidateRequest::slot_planes); a view without them, or options.iterations 0, is unchanged.
/// The flow is OpenCV's DIS (flow_preset) on the luminance, computed where the slot is visible,
/// the blend standing in for it elsewhere. Throws std::invalid_argument on an unknown preset.
void AlignSlots(const SlotAlignmentOptions& options, ViewCandidates* c);

/// OpenCV's cv::DISOpticalFlow preset of `name` (SlotAlignmentOptions::flow_preset); throws
/// std::invalid_argument naming the choices otherwise.
int DisPreset(const std::string& name);

}  // namespace p2i::fusion
