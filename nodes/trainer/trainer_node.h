/// @file trainer_node.h
/// @brief The trainer node: replay buffer fed from "rgbd" (online) or a dataset folder
/// (offline), continuous training, ModelVersion / TrainerStatus publishing.
#pragma once

#include <atomic>
#include <memory>

#include "nodes/runtime/node.h"
#include "nodes/trainer/rank_sync.h"
#include "nodes/trainer/replay_buffer.h"
#include "nodes/trainer/training_loop.h"

namespace p2i::trainer {

/// Parameters: TrainerNodeOptions (trainer_node_options.h); parameters and topics:
/// docs/TRAINER.md. Training runs on the TrainingLoop's thread; frames
/// are converted and added to the buffer on the executor thread; ModelVersion ("model_version",
/// latched) and TrainerStatus ("trainer_status") are published from the training thread through
/// the runtime's locking publishers, and TrainerStatus also every `trainer_status_period` s from
/// a timer. Data-parallel (world_size > 1): the node keeps only its rank's shard of the frames
/// (RankSync::Keeps; the others are counted as `frames_other_rank`) and only rank 0 publishes
/// ModelVersions (TrainingLoop). Thread-safety: as runtime::Node.
class TrainerNode : public runtime::Node {
 public:
  explicit TrainerNode(const runtime::NodeArgs& args);
  ~TrainerNode() override;

 protected:
  void OnShutdown() override;

 private:
  void OnFrame(const msgs::RgbdFrame& frame);
  /// This process's rank (its shard of the frames) and the NodeStatus values naming it.
  void SetRank(const model::DistributedOptions& distributed);

  double shutdown_wait_s_ = 1.0;
  RankSync ranks_{model::DistributedOptions()};  ///< this process's rank: its shard of frames
  /// Set in OnShutdown: the training thread no longer publishes (sockets are about to close).
  std::atomic<bool> closing_{false};
  std::unique_ptr<ReplayBuffer> buffer_;
  std::unique_ptr<TrainingLoop> loop_;
  std::shared_ptr<runtime::Publisher<msgs::pb::ModelVersion>> version_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::TrainerStatus>> status_pub_;
  std::shared_ptr<runtime::RawSubscriber> frame_sub_;
};

}  // namespace p2i::trainer
