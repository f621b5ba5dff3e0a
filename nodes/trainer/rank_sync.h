/// @file rank_sync.h
/// @brief What the trainer node's data-parallel ranks agree on around each training round
/// (docs/DISTRIBUTED.md): the frame shard a rank keeps, the round's frame count, and rank 0's
/// checkpoint as every rank's start. The gradients themselves are averaged inside
/// model::Trainer (TrainerOptions::distributed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "model/distributed.h"

namespace p2i::trainer {

/// The data-parallel side of the TrainingLoop's rounds; with world_size 1 every call is a
/// no-op that keeps today's single-process behaviour.
///
/// Each round, every rank calls AgreeFrames() then ShareCheckpoint() (collectives, in that
/// order, before its model::Trainer run), so every rank resumes from the same file: rank 0's
/// work_dir/checkpoint.pt (weights, optimiser state, steps, pose normaliser). Only rank 0 saves
/// checkpoints (model::Trainer), so the other ranks' copies are refreshed from it every round.
/// A rank that is not there within options.timeout_s, or died, makes these calls throw
/// std::runtime_error "... lost contact ...".
///
/// Thread-compatible: one thread (the training thread) makes the collective calls.
class RankSync {
 public:
  explicit RankSync(const model::DistributedOptions& options) : options_(options) {}

  bool Enabled() const { return options_.Enabled(); }
  /// Rank 0 (or the only process): writes versions and poses, publishes ModelVersion.
  bool IsWriter() const { return options_.rank == 0; }
  int Rank() const { return options_.rank; }
  int WorldSize() const { return options_.world_size; }
  const model::DistributedOptions& Options() const { return options_; }

  /// This rank's shard: a frame with sequence number `seq` (its publisher's header seq online,
  /// its index in the dataset offline) belongs to rank seq % world_size.
  bool Keeps(uint64_t seq) const {
    return seq % static_cast<uint64_t>(options_.world_size) ==
           static_cast<uint64_t>(options_.rank);
  }
  /// Collective: the smallest `frames` over the ranks (the round trains on that many frames of
  /// every rank's snapshot, so every shard weighs the same in the averaged gradients).
  size_t AgreeFrames(size_t frames);
  /// Collective: rank 0's `checkpoint` file (which rank 0 must have) becomes every other
  /// rank's `checkpoint` (written atomically).
  void ShareCheckpoint(const std::string& checkpoint);

 private:
  model::DistributedOptions options_;
};

}  // namespace p2i::trainer
