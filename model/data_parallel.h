/// @file data_parallel.h
/// @brief The ranks of one data-parallel run: rendezvous (c10d TCPStore), a ProcessGroupGloo,
/// parameter broadcast from rank 0 and gradient averaging (one flat all-reduce per optimiser
/// step). Includes LibTorch: used by model/trainer.cc only.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <torch/torch.h>

#include "model/distributed.h"

namespace p2i::model {

struct Networks;

/// Thread-compatible; every rank must call the same collectives in the same order.
class DataParallel {
 public:
  /// The process-wide group for `options` (created on first use, reused by later training runs
  /// of the process, e.g. the trainer node's rounds). Null when !options.Enabled(). Throws
  /// std::runtime_error naming master, rank and timeout when the rendezvous fails.
  static std::shared_ptr<DataParallel> For(const DistributedOptions& options);
  ~DataParallel();

  int Rank() const { return options_.rank; }
  int WorldSize() const { return options_.world_size; }
  /// Only rank 0 writes checkpoints.
  bool IsWriter() const { return options_.rank == 0; }

  /// Copies rank 0's values into every rank's `tensors` (parameters at start and on resume).
  void Broadcast(const std::vector<torch::Tensor>& tensors);
  /// Replaces every defined gradient of `params` by its mean over the ranks (one flat
  /// all-reduce). The divergence guard's decision rides in the same all-reduce: `diverged` is
  /// this rank's verdict on the loss, one more float32 at the end of the buffer, and the result
  /// is true on every rank when any rank's was (so every rank rolls back, or none). Throws
  /// std::runtime_error "... lost contact ..." when a rank died or timed out.
  bool AverageGradients(const std::vector<torch::Tensor>& params, bool diverged = false);
  /// The optimiser's parameters' gradients (call between backward() and step()).
  bool AverageGradients(torch::optim::Optimizer& optimizer, bool diverged = false);
  /// Start of a run: every rank must be at the same steps (resume from the same checkpoint),
  /// then all parameters and buffers of `nets` are copied from rank 0.
  void Start(const int* phase1_step, const int* phase2_step, Networks& nets);
  /// True on every rank if `flag` is true on any (a stop request reaches all ranks).
  bool Any(bool flag);
  /// Throws std::runtime_error unless every rank passes the same `value` (e.g. resume steps).
  void Agree(int64_t value, const std::string& what);
  /// The element-wise smallest `values` over the ranks (every rank passes as many; `what`
  /// names it in a lost-contact error). Exact for integers up to 2^53.
  std::vector<double> Min(const std::vector<double>& values, const std::string& what);
  /// Rank 0's `bytes` on every rank (its size first, then the bytes; `what` as for Min).
  std::string BroadcastBytes(const std::string& bytes, const std::string& what);

  /// Bytes all-reduced per AverageGradients call (last call: the gradients as float32 plus the
  /// 4-byte divergence flag) and the time spent in them.
  int64_t LastAllReduceBytes() const { return last_bytes_; }
  /// Writes DIR/distributed.rank<R>.json (steps, bytes per step, all-reduce ms mean/p50/max).
  void WriteStats(const std::string& dir) const;

 private:
  explicit DataParallel(const DistributedOptions& options);
  [[noreturn]] void Lost(const std::string& during, const std::exception& e) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  DistributedOptions options_;
  int64_t last_bytes_ = 0;
  std::vector<double> allreduce_ms_;
  std::vector<int64_t> allreduce_bytes_;
};

}  // namespace p2i::model
