/// @file trainer.h
/// @brief Two-phase P2I-NET training (phase 1: G and D adversarial; phase 2: ENET with G frozen)
/// and the CNN baseline's L2 regression, with checkpoints, exact resume, a divergence guard,
/// a terminal progress bar and a JSON-lines log. Torch-free header (the trainer node and the
/// `p2i train` tool use it).
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "model/distributed.h"
#include "model/p2i_config.h"
#include "scene/rgbd_sample.h"

namespace p2i::model {

/// How one training run is carried out (the model itself is in P2iConfig).
struct TrainerOptions {
  std::string out_dir;      ///< checkpoint.pt and train_log.jsonl go here (created if needed)
  int phase = 0;            ///< 0 = phase 1 then 2, 1 = phase 1 only, 2 = phase 2 only
  int steps = -1;           ///< >= 0: run to this many steps in each phase run (else the config's)
  /// >= 0: phase 2's target step instead of `steps` (the trainer node runs phase 1 and 2 to
  /// different step counts in one call).
  int steps_phase2 = -1;
  int threads = 2;          ///< torch::set_num_threads
  /// Continue from out_dir/checkpoint.pt exactly. If that file is an inference checkpoint (an
  /// exported file copied there), this is a warm start from it instead (see init_from).
  bool resume = false;
  /// Warm start when not resuming: G and ENET weights, pose normalisation, camera and step
  /// counters come from this checkpoint (full or inference; same network shape as the config),
  /// D and the optimisers start fresh. Training continues to `steps` counted from its steps.
  std::string init_from;
  bool progress = true;     ///< progress bar on stderr
  int max_val_frames = 32;  ///< held-out frames used for the validation PSNR
  int max_rollbacks = 5;    ///< divergence-guard rollbacks before giving up
  /// Fault injection for tests: poison the phase-1 loss with NaN once at this step (-1 = never).
  int inject_nan_at_step = -1;
  std::function<bool()> should_stop;  ///< polled between steps; true = save a checkpoint now and return
  /// Data-parallel ranks (model/distributed.h, docs/DISTRIBUTED.md); world_size 1 = off.
  DistributedOptions distributed;

  void Validate() const;
};

/// What a run ended with.
struct TrainReport {
  int phase1_steps = 0;
  int phase2_steps = 0;
  int rollbacks = 0;
  bool stopped = false;               ///< should_stop() ended the run early (checkpoint saved)
  double val_psnr = 0.0;              ///< last validation PSNR (dB, RGB), 0 if none
  double mean_image_val_psnr = 0.0;   ///< PSNR of predicting the mean training image
  /// Last validation pose-dependence score (model/pose_dependence.h: 1 = varies like the scene,
  /// 0 = one image for every pose); NaN if no validation ran.
  double val_pose_dependence = std::numeric_limits<double>::quiet_NaN();
  std::string checkpoint_path;
  std::string log_path;
};

/// Trains one model. Run() is blocking and single-threaded from the caller's side (LibTorch uses
/// `threads` worker threads). Not thread-safe; one Run per instance at a time. Throws
/// std::invalid_argument on bad options/data and std::runtime_error on IO or unrecoverable
/// divergence.
class Trainer {
 public:
  Trainer(P2iConfig config, TrainerOptions options);
  ~Trainer();

  /// `train` and `val` frames of any size (centre-cropped and resized to the config's
  /// resolution); `val` may be empty (no validation PSNR then).
  TrainReport Run(const scene::RgbdDataset& train, const scene::RgbdDataset& val);

  static std::string CheckpointPath(const std::string& out_dir);

 private:
  P2iConfig config_;
  TrainerOptions options_;
};

}  // namespace p2i::model
