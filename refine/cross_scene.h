/// @file cross_scene.h
/// @brief Trains the shipped cross-scene refinement net: leave-one-out samples from randomised
/// sim scenes (refine/sim_scenes.h), one Adam run over all of them, evaluated on held-out
/// scenes (never trained on) against the plain blend.
#pragma once

#include <string>

#include "model/refine_options.h"
#include "model/refiner.h"
#include "refine/leave_one_out.h"
#include "refine/sim_scenes.h"

namespace p2i::refine {

struct CrossSceneOptions {
  SimScenesOptions scenes;         ///< frames rendered at scenes.width x scenes.height
  int held_out_scenes = 1;         ///< the last ones: validation only
  LeaveOneOutOptions loo;
  model::RefineNetOptions net;     ///< in_channels from k
  model::RefineTrainOptions fit;
  void Validate() const;
};

struct CrossSceneReport {
  int train_samples = 0;
  int val_samples = 0;
  model::RefineFitReport fit;
  model::RefineEval val;           ///< held-out scenes: refined vs blend
  double seconds_samples = 0.0;
  double seconds_fit = 0.0;
  int64_t parameters = 0;
};

/// Trains and writes the net to `out_path` (atomically), its metadata naming the scenes.
CrossSceneReport TrainCrossScene(const CrossSceneOptions& options, const std::string& out_path);

}  // namespace p2i::refine
