/// @file trainer_node.h
/// @brief The trainer node: replay buffer fed from "rgbd" (online) or a dataset folder
/// (offline), continuous training, ModelVersion / TrainerStatus publishing; with method fusion,
/// online mapping instead (FusionMapper: TSDF + keyframes, fusion versions).
#pragma once

#include <atomic>
#include <memory>

#include "nodes/runtime/node.h"
#include "nodes/trainer/fusion_mapper.h"
#include "nodes/trainer/rank_sync.h"
#include "nodes/trainer/replay_buffer.h"
#include "nodes/trainer/training_loop.h"

namespace p2i::trainer {

struct TrainerNodeOptions;

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
  // Start-up of the two methods, after the parameters are read and the publishers advertised.
  void StartTraining(TrainerNodeOptions& options, const std::string& work_dir);  // p2i
  void StartMapper(TrainerNodeOptions& options, const std::string& work_dir);    // fusion
  void PublishMapperStatus();  // method fusion: TrainerStatus + NodeStatus values
  void OnFrame(const msgs::RgbdFrame& frame);
  /// This process's rank (its shard of the frames) and the NodeStatus values naming it.
  void SetRank(const model::DistributedOptions& distributed);

  double shutdown_wait_s_ = 1.0;
  RankSync ranks_{model::DistributedOptions()};  ///< this process's rank: its shard of frames
  /// Set in OnShutdown: the training thread no longer publishes (sockets are about to close).
  std::atomic<bool> closing_{false};
  std::unique_ptr<ReplayBuffer> buffer_;
  std::unique_ptr<TrainingLoop> loop_;
  std::unique_ptr<FusionMapper> mapper_;  ///< method fusion (then no buffer_ and no loop_)
  std::string last_mapper_error_;         ///< logged once per new mapping error
  bool mapper_refines_ = false;           ///< method fusion with refine_finetune_steps > 0
  std::string last_refine_error_;         ///< logged once per new fine-tuning message
  std::shared_ptr<runtime::Publisher<msgs::pb::ModelVersion>> version_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::TrainerStatus>> status_pub_;
  std::shared_ptr<runtime::RawSubscriber> frame_sub_;
};

}  // namespace p2i::trainer
