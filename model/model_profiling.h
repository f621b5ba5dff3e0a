/// @file model_profiling.h
/// @brief Torch-free helpers for bench/model_bench.cc: the machine's matmul FLOP rate, the time
/// of one training step, and an untrained checkpoint for inference timing.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "model/p2i_config.h"

namespace p2i::model {

/// FLOP/s of an n x n float matmul on `threads` LibTorch threads (best of `reps`).
double MeasureMatmulFlopRate(int n, int threads, int reps = 5);

/// Median wall time (seconds) of one training step of `phase` (1: D + G step, or the baseline's
/// regression step; 2: ENET step) at config.batch_size on random data, over `steps` steps
/// after one warm-up step. The G step runs with D frozen (model::FrozenScope), as the trainer's;
/// `freeze_d = false` times it as before that change (D's weight gradients computed too).
double TimeTrainingStep(const P2iConfig& config, int phase, int steps, int threads,
                        bool freeze_d = true);

/// Where the time of one phase-1 (G + D) step goes, in seconds per step (mean over `steps`
/// after a warm-up step), each section synchronous (CPU): G forward; D forward on the reals and
/// on the detached fakes; L_D + D backward; D's Adam; D forward on the fakes for G; L_G +
/// backward through D and G; G's Adam. `attention` and `spectral_norm` are measured apart
/// (inside D's forward/backward above): the self-attention blocks' forward on inputs of their
/// size, and one power iteration on every SN weight, both as in D's forward of the D step.
struct StepProfile {
  std::vector<std::pair<std::string, double>> sections;
  double total = 0.0;  ///< sum of the step's own sections (without the two apart)
};
StepProfile ProfileTrainingStep(const P2iConfig& config, int steps, int threads,
                                bool freeze_d = true);

/// Multiply-accumulate FLOPs (2 x MACs) of one training step: forward + backward ~ 3x forward
/// of every network the step runs, times the batch size.
double TrainingStepFlops(const P2iConfig& config, int phase);

/// Writes a freshly initialised checkpoint of `config` (phase-2 step marked done when ENET is on,
/// so the synthesizer runs G + ENET), for timing inference.
void WriteUntrainedCheckpoint(const P2iConfig& config, const std::string& path);

}  // namespace p2i::model
