/// @file trainer_node.cc
/// @brief TrainerNode: parameters, frame intake, publishing.
#include "nodes/trainer/trainer_node.h"

#include <cmath>
#include <filesystem>

#include "convert/camera_info.h"
#include "convert/rgbd_frame.h"
#include "model/p2i_config.h"
#include "model/pose_dependence.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/trainer/trainer_node_options.h"
#include "scene/dataset_loader.h"

namespace p2i::trainer {

TrainerNode::TrainerNode(const runtime::NodeArgs& args) : Node("trainer", args) {
  TrainerNodeOptions options = TrainerNodeOptions::FromParameters(Params());
  options.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  shutdown_wait_s_ = options.shutdown_wait;
  ParametersDone();
  SetRank(options.loop.distributed);

  model::P2iConfig config = options.config_file.empty()
                                ? model::P2iConfig()
                                : model::P2iConfig::FromYamlFile(options.config_file);
  if (options.resolution > 0) {
    config.resolution = options.resolution;
    if (config.g_schedule == "custom") {
      // Keep the per-stage widths consistent with the new resolution (one per stage).
      const int stages = static_cast<int>(std::log2(options.resolution)) - 1;
      std::vector<int> w = config.g_widths;
      w.resize(stages, w.empty() ? 32 : w.back());
      config.g_widths = w;
    }
  }
  config.Validate();
  const std::string work_dir =
      options.work_dir.empty() ? runtime::RunDir() + "/" + Name() : options.work_dir;

  ReplayBuffer::Options& b = options.buffer;
  b.dir = work_dir + "/buffer";
  b.width = b.height = config.resolution;
  b.seed = config.seed;
  buffer_ = std::make_unique<ReplayBuffer>(b);
  Log().info("replay buffer: capacity {} frames ({} recent), {} reloaded from {}",
             buffer_->Capacity(), buffer_->RecentCapacity(), buffer_->Reloaded(), b.dir);

  runtime::PublisherOptions latched;
  latched.latched = true;
  version_pub_ = Advertise<msgs::pb::ModelVersion>("model_version", latched);
  status_pub_ = Advertise<msgs::pb::TrainerStatus>("trainer_status");

  const std::string& dataset = options.dataset;
  if (!dataset.empty()) {
    const scene::DatasetIndex index = scene::OpenDataset(dataset);
    for (size_t i = 0; i < index.size(); ++i)
      if (ranks_.Keeps(i)) buffer_->Add(index.Load(i), index.camera());
    Log().info("offline: {} frames from {} (buffer holds {})", index.size(), dataset,
               buffer_->Size());
  } else {
    frame_sub_ = Subscribe<msgs::RgbdFrame>("rgbd", [this](const msgs::RgbdFrame& f) {
      OnFrame(f);
    });
  }

  TrainingLoop::Options o = options.Loop();
  o.config = config;
  o.work_dir = work_dir;
  loop_ = std::make_unique<TrainingLoop>(
      o, buffer_.get(),
      [this](const msgs::pb::ModelVersion& v) {
        if (closing_) return;  // a round that ended during shutdown: its file stays on disk
        version_pub_->Publish(v);
        Count("versions_published");
        SetValue("val_psnr", v.val_psnr());
        // In this node's NodeStatus values (p2i topic echo /trainer/node_status).
        const double pose_dependence = loop_->LastPoseDependence();
        SetValue("val_pose_dependence", pose_dependence);
        Log().info("model version {} (step {}, val PSNR {:.2f} dB, pose-dependence {:.2f}): {}",
                   v.version(), v.step(), v.val_psnr(), pose_dependence, v.checkpoint_path());
        if (pose_dependence >= 0 && pose_dependence < model::kPoseDependenceWarn)
          Log().warn("{}", model::PoseDependenceWarning(pose_dependence));
      },
      [this](const msgs::pb::TrainerStatus& s) {
        // The loop's last status says what ended it (a lost rank, or another rank's stop).
        if ((s.phase() == "error" || s.phase() == "stopped") && !s.error().empty())
          Log().warn("training ended (phase {}): {}", s.phase(), s.error());
        if (!closing_) status_pub_->Publish(s);
      });
  if (options.trainer_status_period > 0)
    AddTimer(std::chrono::nanoseconds(static_cast<int64_t>(options.trainer_status_period * 1e9)),
             [this] { status_pub_->Publish(loop_->LastStatus()); });
  loop_->Start();
}

TrainerNode::~TrainerNode() = default;

void TrainerNode::SetRank(const model::DistributedOptions& distributed) {
  ranks_ = RankSync(distributed);
  SetValue("world_size", ranks_.WorldSize());
  SetValue("rank", ranks_.Rank());
  if (ranks_.Enabled())
    Log().info("data-parallel rank {} of {} (master {}): frames with seq % {} == {}, {}",
               ranks_.Rank(), ranks_.WorldSize(), distributed.master, ranks_.WorldSize(),
               ranks_.Rank(),
               ranks_.IsWriter() ? "publishes the versions" : "publishes no versions");
}

void TrainerNode::OnFrame(const msgs::RgbdFrame& frame) {
  Count("frames_received");
  if (!ranks_.Keeps(frame.meta.header().seq())) {
    Count("frames_other_rank");
    return;
  }
  if (!frame.meta.has_camera_info()) {
    Count("frames_without_camera_info");
    WarnThrottled("no_camera_info", "dropping a frame without inline camera_info");
    return;
  }
  try {
    const scene::CameraInfo camera = convert::FromMsg(frame.meta.camera_info());
    if (!buffer_->Add(convert::ToSample(frame), camera, frame.meta.has_pose())) {
      Count("frames_without_pose");
      return;
    }
    Count("frames_accepted");
    SetValue("buffer_size", static_cast<double>(buffer_->Size()));
  } catch (const std::exception& e) {
    Count("frames_rejected");
    WarnThrottled("frame", std::string("dropping a frame: ") + e.what());
  }
}

void TrainerNode::OnShutdown() {
  if (!loop_) return;
  closing_ = true;
  // The round stops at its next step boundary and saves checkpoint.pt (TrainingLoop::Stop).
  const auto t0 = std::chrono::steady_clock::now();
  if (!loop_->Stop(std::chrono::milliseconds(static_cast<int64_t>(shutdown_wait_s_ * 1000)))) {
    Log().warn("waiting for the training round to reach a step boundary and save its checkpoint");
    loop_->Join();
  }
  Log().info("training stopped after {:.2f} s at step {} (checkpoint saved; a restart resumes "
             "there)",
             std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
             loop_->LastStatus().step());
  if (!loop_->Error().empty()) Log().error("training stopped with an error: {}", loop_->Error());
}

}  // namespace p2i::trainer
