/// @file evaluation.h
/// @brief Figures of the refinement on one train/test split: nearest keyframe, depth warp, the
/// plain fusion blend, the refinement zero-shot (a given net) and fine-tuned on the split's own
/// leave-one-out samples, all at one resolution on the same test frames.
#pragma once

#include <string>
#include <vector>

#include "model/refine_options.h"
#include "refine/leave_one_out.h"
#include "scene/rgbd_sample.h"

namespace p2i::refine {

struct SplitEvalOptions {
  int width = 128;                 ///< views and ground truth: centre crop + resize of the frames
  int height = 128;
  int fuse_width = 320;            ///< frames are resized to this before fusing (0 = as given)
  int fuse_height = 240;
  LeaveOneOutOptions loo;          ///< fine-tuning samples from the training frames
  model::RefineTrainOptions finetune;  ///< fine-tuning of the zero-shot net (steps 0 = none)
  bool scratch = true;             ///< also train a fresh per-scene net with `finetune`
  int warp_k = 4;
  void Validate() const;
};

struct MethodScore {
  std::string method;
  double psnr = 0.0;
  double ssim = 0.0;
  double abs_rel = 0.0;            ///< mean over views with valid depth
  double observed = 0.0;           ///< fusion: mean observed fraction of the views
  int views = 0;
};

struct SplitEvalReport {
  std::vector<MethodScore> methods;
  int train_frames = 0;
  int test_frames = 0;
  int loo_samples = 0;
  double finetune_first_loss = 0.0;
  double finetune_last_loss = 0.0;
  double finetune_seconds = 0.0;
};

/// `net_path`: the zero-shot refinement file ("" = skip zero-shot and fine-tuning from it).
SplitEvalReport EvaluateSplit(const scene::RgbdDataset& train, const scene::RgbdDataset& test,
                              const std::string& net_path, const SplitEvalOptions& options);

}  // namespace p2i::refine
