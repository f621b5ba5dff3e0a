/// @file distributed.h
/// @brief Data-parallel training over torch's c10d ProcessGroupGloo (docs/DISTRIBUTED.md).
/// Torch-free: TrainerOptions carries DistributedOptions; model/trainer.cc calls the hooks of
/// DataParallel (model/data_parallel.h, torch) between its steps.
#pragma once

#include <cstdint>
#include <string>

namespace p2i::model {

/// True when `s` is HOST:PORT with a port in 1..65535 (the form of DistributedOptions::master).
bool IsHostPort(const std::string& s);

/// `p2i train --world-size N --rank R --master HOST:PORT` (and the trainer node's world_size,
/// rank, master parameters). world_size 1 = ordinary single-process training.
struct DistributedOptions {
  int world_size = 1;
  int rank = 0;
  std::string master;         ///< HOST:PORT of rank 0's rendezvous store (TCP)
  /// This rank's address for the Gloo connections; "" = 127.0.0.1 when the master is on
  /// loopback, else the address the host name resolves to.
  std::string address;
  double timeout_s = 60.0;    ///< rendezvous and every collective; a dead rank ends it sooner

  bool Enabled() const { return world_size > 1; }
  /// Throws std::invalid_argument naming the option (rank range, HOST:PORT form, timeout).
  void Validate() const;
};

// Collectives of the process-wide group of `options` (DataParallel::For: the first call meets
// the other ranks), for code that must not include LibTorch (the trainer node's rounds,
// nodes/trainer/rank_sync.h). Every rank must make the same calls in the same order as the
// others, interleaved with its training runs' collectives alike. They throw
// std::runtime_error "... lost contact ..." when a rank died or did not arrive within
// options.timeout_s, and std::logic_error unless options.Enabled().

/// The smallest `value` over the ranks.
int64_t MinOverRanks(const DistributedOptions& options, int64_t value);
/// Rank 0's `bytes` on every rank (the other ranks' argument is ignored).
std::string BroadcastFromRankZero(const DistributedOptions& options, const std::string& bytes);

}  // namespace p2i::model
