/// @file fusion_method.h
/// @brief The registry entry of the `fusion` method (model/method_registry.cc lists it): fusion/'s
/// TSDF + view-dependent keyframe blend (fusion::FusionSynthesizer) with the optional learned
/// refinement (model::LearnedRefiner), loaded from a refinement file (the shipped cross-scene
/// models/refine_sim.pt) and/or fine-tuned by leave-one-out on the method's own training frames
/// when the method is built. Lives here, not in fusion/, because the fine-tuning samples are
/// refine/'s (leave_one_out.h).
#pragma once

#include <string>
#include <vector>

#include "model/method_registry.h"
#include "model/refine_options.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::refine {

/// The `refine: {...}` map of the fusion method's options.
struct FusionRefineOptions {
  /// Refinement file (a model::Refiner save: `p2i refine train-sim`), "" = none. A relative path
  /// is taken relative to the folder of the file the options came from (a bench config), or to
  /// the working directory when they came from elsewhere (a node parameter).
  std::string net;
  /// Leave-one-out fine-tuning steps on the training frames when the method is built (0 = use the
  /// net as it is, zero-shot). With no `net`, a fresh net is trained from scratch.
  int finetune_steps = 0;
  int folds = 4;            ///< refine::LeaveOneOutOptions::folds
  int keyframe_every = 1;   ///< refine::LeaveOneOutOptions::keyframe_every
  /// lr, batch_size, crop, ssim_weight, depth_weight, seed of the fine-tuning (steps and threads
  /// are set from finetune_steps and the method's threads).
  model::RefineTrainOptions train;

  /// True when the views are refined (a net is named or trained).
  bool Enabled() const { return !net.empty() || finetune_steps > 0; }
  /// Reads the map (keys: net, finetune_steps, folds, keyframe_every, lr, batch_size, crop,
  /// ssim_weight, depth_weight, seed), resolves `net` and checks that it exists. Throws
  /// std::runtime_error naming `source`, the line and the key.
  static FusionRefineOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field and its value.
  void Validate() const;
};

/// The fusion method's option keys: fusion::FusionOptionKeys() plus "refine" and "p2i_fill" (a
/// P2I-NET checkpoint trained on the same frames at the view's resolution: its G (+ ENET) view
/// fills the pixels the TSDF never observed, FusionSynthesizer::SetHoleFiller; a relative path is
/// resolved like refine.net).
const std::vector<std::string>& FusionMethodOptionKeys();

/// Reads {tsdf, blend, fill_holes, refine} (null = defaults: no refinement), checks them once and
/// returns a factory building the `fusion` method over MethodInputs::training: every frame fused
/// and kept as a keyframe, the refiner loaded and fine-tuned (MethodInputs::threads) when
/// `refine` asks for it. Bad keys, values or a missing net file throw std::runtime_error naming
/// `source`, the line and the key.
model::MethodFactory ConfigureFusionMethod(const YAML::Node& options, const std::string& source);

}  // namespace p2i::refine
