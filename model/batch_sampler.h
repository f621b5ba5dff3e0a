/// @file batch_sampler.h
/// @brief Which training frames a step's batch holds (TrainingRun, model/trainer.cc): a pure
/// function of (seed, phase, step), so a resumed run draws the batches the uninterrupted one
/// would have. Torch-free.
#pragma once

#include <cstdint>
#include <vector>

namespace p2i::model {

/// What one batch is drawn from.
struct BatchDraw {
  uint64_t seed = 1;
  int phase = 1;        ///< 1 and 2 (the training phases), 100 + k (phase 1's extra D batches)
  int step = 0;
  int batch_size = 16;  ///< per rank
  int world = 1;        ///< data-parallel ranks: one global batch of batch_size x world
  int rank = 0;         ///< this rank's slice of the global batch
};

/// Indices into `n` frames, uniform over all of them: the draws of every run without
/// densify_real_share (unchanged, so earlier runs reproduce).
std::vector<int64_t> DrawBatch(const BatchDraw& d, int64_t n);

/// Indices with a share of captured frames (P2iConfig::densify_real_share): each entry comes
/// from `captured` with probability `real_share`, else from `densified`, uniform within each
/// (real_share 1: captured frames only, as past P2iConfig::densify_steps). Falls back to
/// DrawBatch over captured.size() + densified.size() frames when either list is empty or
/// real_share is 0.
std::vector<int64_t> DrawMixedBatch(const BatchDraw& d, const std::vector<int64_t>& captured,
                                    const std::vector<int64_t>& densified, double real_share);

}  // namespace p2i::model
