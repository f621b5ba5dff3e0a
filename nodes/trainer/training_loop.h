/// @file training_loop.h
/// @brief Trains P2I-NET in rounds on a ReplayBuffer on its own thread and hands out a new
/// model version (versioned checkpoint file + validation PSNR) after every round.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "model/distributed.h"
#include "model/p2i_config.h"
#include "model/trainer.h"
#include "msgs/p2i.pb.h"
#include "nodes/trainer/rank_sync.h"
#include "nodes/trainer/replay_buffer.h"

namespace p2i::trainer {

/// Continuous training in rounds.
///
/// Each round snapshots the buffer (every `val_every_nth` frame held out for validation once
/// the buffer has at least 2 * val_every_nth frames), runs model::Trainer (G and D for
/// `steps_per_round` more steps, then ENET for `enet_steps_per_round` more steps with that G
/// frozen) with `resume` so weights, optimiser state and RNG carry over, then copies work_dir/checkpoint.pt atomically to
/// work_dir/versions/model_vNNNNNN.pt (after writing the round's training poses beside it,
/// model_vNNNNNN.poses.txt, TUM format, atomically) and calls `on_version`. A status (`on_status`) is emitted
/// when the phase changes and after each round. Versions continue after a restart (the highest
/// file in versions/ is found); the trainer resumes from work_dir/checkpoint.pt if present, else
/// from `warm_start` (copied into the work dir first), else from scratch.
///
/// Stop: the loop passes model::TrainerOptions::should_stop (polled between training steps) to
/// every round, so Stop() interrupts a running round at the next step boundary: the trainer
/// saves work_dir/checkpoint.pt at that step (atomically) and returns; the partial round is not
/// published as a version, and the next start resumes from that checkpoint. Only a round's
/// set-up (dataset preparation, checkpoint load) and one step are not interruptible.
/// Published versions are never touched again.
///
/// Data-parallel (`distributed.world_size` > 1, docs/DISTRIBUTED.md): one loop per rank
/// process, each on its own buffer (the node keeps the rank's shard of the frames). Between
/// rounds the ranks poll each other every 100 ms (RankSync::Poll, nodes/trainer/rank_sync.h):
/// a round starts on all of them at once when every rank holds min_frames, on the round's
/// frame count n (the smallest snapshot; each trains on the first n frames of its own), and
/// every rank resumes from rank 0's checkpoint (for a fresh start all ranks first run a 0-step
/// round together, so the pose normaliser is that of every rank's frames); model::Trainer
/// then averages the gradients of every step and takes its divergence rollbacks on all ranks
/// together. Only rank 0 writes versions and poses and calls `on_version`. A rank that died
/// or timed out ends the loop with the "lost contact" error (Error(), and phase "error" with
/// that `error` in TrainerStatus). A stop of any rank stops all: during a round at the same
/// step, between rounds at the same poll; the others end in phase "stopped" with TrainerStatus
/// `error` saying which rank stopped (StopReason()).
///
/// Thread-safety: Start/Stop from one thread; callbacks run on the training thread (the caller
/// must make them thread-safe, e.g. with locking publishers); LastStatus() is thread-safe.
class TrainingLoop {
 public:
  struct Options {
    model::P2iConfig config;
    std::string work_dir;
    int steps_per_round = 200;
    /// ENET (phase-2) steps per round, after the round's G + D steps, on the round's G (so each
    /// published version pairs G with an ENET trained on it); -1 = steps_per_round, 0 = G only.
    /// Ignored when the config has no ENET.
    int enet_steps_per_round = -1;
    int threads = 1;              ///< torch threads for training
    std::string warm_start;       ///< checkpoint to start from ("" = none)
    size_t min_frames = 8;        ///< the loop waits until the buffer holds this many
    int val_every_nth = 8;        ///< every n-th buffer frame is validation
    int max_val_frames = 8;
    int max_rounds = -1;          ///< stop after this many rounds (-1 = never; tests, offline)
    model::DistributedOptions distributed;  ///< world_size 1 = this process only

    void Validate() const;
  };
  using VersionCallback = std::function<void(const msgs::pb::ModelVersion&)>;
  using StatusCallback = std::function<void(const msgs::pb::TrainerStatus&)>;

  TrainingLoop(const Options& options, ReplayBuffer* buffer, VersionCallback on_version,
               StatusCallback on_status);
  ~TrainingLoop();  ///< Stop() and join (at most the rest of one step)

  void Start();
  /// Asks the thread to stop and waits up to `wait`; true when it has ended (then joined).
  bool Stop(std::chrono::milliseconds wait);
  /// Asks the thread to stop and waits until it has ended.
  void Join();
  bool Finished() const { return finished_; }
  /// The error that ended the thread ("" if none).
  std::string Error() const;
  /// Data-parallel: why this loop stopped when another rank's stop ended it ("" otherwise).
  std::string StopReason() const;
  msgs::pb::TrainerStatus LastStatus() const;
  uint64_t LastVersion() const { return version_; }
  /// Pose-dependence score (model/pose_dependence.h) of the last published version's validation;
  /// -1 before the first one (or without validation frames). Thread-safe.
  double LastPoseDependence() const { return pose_dependence_; }

  static std::string VersionPath(const std::string& work_dir, uint64_t version);
  /// versions/model_vNNNNNN.poses.txt beside a version's checkpoint: the TUM poses of the frames
  /// that round trained on (ModelVersion.poses_path).
  static std::string PosesPath(const std::string& version_path);

 private:
  /// A round's frames: every val_every_nth one held out once there are 2 * val_every_nth.
  struct RoundData {
    scene::RgbdDataset train, val;
  };
  /// Where the rounds are: the checkpoint's steps (known after the first round when resuming).
  struct Progress {
    int step = 0;   ///< phase-1 step of the checkpoint
    int step2 = 0;  ///< phase-2 (ENET) step of the checkpoint
    bool know_step = false;
    int rounds = 0;
  };

  void Main();
  void RunRounds();
  bool WaitForRound(RankSync& ranks, const Progress& progress, scene::RgbdDataset* all);
  void StoppedBy(const std::string& reason);
  RoundData HoldOut(const scene::RgbdDataset& all) const;
  void StartFromRankZero(RankSync& ranks, const RoundData& data);
  model::TrainReport TrainRound(const Progress& progress, const RoundData& data);
  void RecordRound(const model::TrainReport& report, double seconds, Progress* progress);
  void PublishVersion(const model::TrainReport& report, const RoundData& data, int step);
  void SetPhase(const std::string& phase);
  void EmitStatus();
  void ReadLosses();
  void WriteFirstCheckpoint(const scene::RgbdDataset& train, const scene::RgbdDataset& val);

  Options options_;
  ReplayBuffer* buffer_;
  VersionCallback on_version_;
  StatusCallback on_status_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};
  std::atomic<uint64_t> version_{0};
  std::atomic<double> pose_dependence_{-1.0};
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  msgs::pb::TrainerStatus status_;
  std::string error_;
  std::string stop_reason_;
};

}  // namespace p2i::trainer
