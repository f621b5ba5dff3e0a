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

/// What the ranks told each other in one RankSync::Poll between rounds.
struct RoundPoll {
  /// The round's frame count: the smallest snapshot over the ranks when every rank is ready
  /// (holds its min_frames), else 0 (every rank waits and polls again).
  size_t frames = 0;
  int stopped_rank = -1;   ///< the lowest rank whose loop is stopping (node shutdown); -1 none
  int finished_rank = -1;  ///< the lowest rank that has run its max_rounds; -1 none
};

/// The data-parallel side of the TrainingLoop's rounds; with world_size 1 every call is a
/// no-op that keeps today's single-process behaviour.
///
/// Between rounds every rank calls Poll() every ~100 ms (a collective: the ranks move in step),
/// so a round starts on every rank at the same poll, and a rank that stops or finishes
/// announces it in its last poll: the others leave at that same poll, cleanly, instead of
/// waiting for it at the next collective. Each round then calls ShareCheckpoint() (before its
/// model::Trainer run), so every rank resumes from the same file: rank 0's
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
  /// Collective between rounds: `ready_frames` is this rank's snapshot size when it holds its
  /// min_frames, else 0; `stopping` / `finished`: this rank leaves after this poll (Stop(), or
  /// its max_rounds). The round then trains on the first RoundPoll::frames frames of every
  /// rank's snapshot, so every shard weighs the same in the averaged gradients.
  RoundPoll Poll(size_t ready_frames, bool stopping, bool finished);
  /// Collective: rank 0's `checkpoint` file becomes every other rank's `checkpoint` (written
  /// atomically). False on every rank (nothing written) when rank 0 has none yet.
  bool ShareCheckpoint(const std::string& checkpoint);

 private:
  model::DistributedOptions options_;
};

}  // namespace p2i::trainer
