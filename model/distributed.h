/// @file distributed.h
/// @brief Data-parallel training over torch's c10d ProcessGroupGloo (docs/DISTRIBUTED.md).
/// Torch-free: TrainerOptions carries DistributedOptions; model/trainer.cc calls the hooks of
/// DataParallel (model/data_parallel.h, torch) between its steps.
#pragma once

#include <string>

namespace p2i::model {

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

}  // namespace p2i::model
