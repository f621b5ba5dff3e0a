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
  const std::string work_dir =
      options.work_dir.empty() ? runtime::RunDir() + "/" + Name() : options.work_dir;

  runtime::PublisherOptions latched;
  latched.latched = true;
  version_pub_ = Advertise<msgs::pb::ModelVersion>("model_version", latched);
  status_pub_ = Advertise<msgs::pb::TrainerStatus>("trainer_status");
  if (options.method == "fusion") {
    StartMapper(options, work_dir);
  } else {
    StartTraining(options, work_dir);
  }
}

void TrainerNode::StartTraining(TrainerNodeOptions& options, const std::string& work_dir) {
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
  if (config.densify_ratio > 0)
    Log().warn("densify_ratio {} in the model config is not used online: the trainer node trains "
               "on the frames it receives (p2i train and p2i bench densify)", config.densify_ratio);

  ReplayBuffer::Options& b = options.buffer;
  b.dir = work_dir + "/buffer";
  b.width = b.height = config.resolution;
  b.seed = config.seed;
  buffer_ = std::make_unique<ReplayBuffer>(b);
  Log().info("replay buffer: capacity {} frames ({} recent), {} reloaded from {}",
             buffer_->Capacity(), buffer_->RecentCapacity(), buffer_->Reloaded(), b.dir);

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

void TrainerNode::StartMapper(TrainerNodeOptions& options, const std::string& work_dir) {
  FusionMapperOptions mo = options.mapper;
  mo.work_dir = work_dir;
  mapper_ = std::make_unique<FusionMapper>(
      mo, [this](const model::FusionVersionManifest& m, const std::string& dir) {
        if (closing_) return;  // the last version of a shutdown stays on disk for a restart
        msgs::pb::ModelVersion v;
        v.set_version(m.version);
        v.set_checkpoint_path(dir);
        v.set_step(m.frames_integrated);
        v.set_method("fusion");
        v.set_width(static_cast<uint32_t>(m.width));
        v.set_height(static_cast<uint32_t>(m.height));
        version_pub_->Publish(v);
        Count("versions_published");
        Log().info("fusion version {} ({} frames integrated, {} keyframes, refinement: {}): {}",
                   m.version, m.frames_integrated, m.keyframe_count,
                   m.refine_file.empty() ? std::string("none")
                   : m.step > 0 ? "fine-tuned online, " + std::to_string(m.step) +
                                      " optimiser steps in all"
                                : std::string("refine_net as it is"),
                   dir);
      });
  Log().info("method fusion: mapping online, a version every {} integrated frames into {}",
             mo.publish_every_frames, mapper_->VersionsDir());
  mapper_refines_ = mo.refine_finetune_steps > 0;
  if (mapper_refines_)
    Log().info("refinement fine-tuned online: {} steps per version on the newest {} keyframes, "
               "from {}", mo.refine_finetune_steps, mo.refine_window_keyframes,
               mo.refine_net.empty() ? std::string("a fresh net") : mo.refine_net);
  if (!options.dataset.empty()) {
    const scene::DatasetIndex index = scene::OpenDataset(options.dataset);
    for (size_t i = 0; i < index.size(); ++i)
      mapper_->Submit(index.Load(i), index.camera(), /*wait=*/true);
    Log().info("offline: {} frames from {} queued for mapping", index.size(), options.dataset);
  } else {
    frame_sub_ = Subscribe<msgs::RgbdFrame>("rgbd", [this](const msgs::RgbdFrame& f) {
      OnFrame(f);
    });
  }
  if (options.trainer_status_period > 0)
    AddTimer(std::chrono::nanoseconds(static_cast<int64_t>(options.trainer_status_period * 1e9)),
             [this] { PublishMapperStatus(); });
}

void TrainerNode::PublishMapperStatus() {
  const FusionMapper::Stats st = mapper_->GetStats();
  SetValue("frames_integrated", static_cast<double>(st.integrated));
  SetValue("keyframes", static_cast<double>(st.keyframes));
  SetValue("frames_dropped_busy", static_cast<double>(st.dropped));
  SetValue("frames_rejected", static_cast<double>(st.rejected));
  SetValue("integrate_ms", st.last_integrate_ms);
  if (mapper_refines_) {
    SetValue("refine_rounds", static_cast<double>(st.refine_rounds));
    SetValue("refine_steps", static_cast<double>(st.refine_steps));
    SetValue("refine_loss", st.refine_loss);
    if (st.refine_error != last_refine_error_) {
      last_refine_error_ = st.refine_error;
      if (!st.refine_error.empty()) Log().info("refinement fine-tuning: {}", st.refine_error);
    }
  }
  if (st.last_error != last_mapper_error_) {
    last_mapper_error_ = st.last_error;
    Log().warn("mapping: {}", st.last_error);
  }
  msgs::pb::TrainerStatus s;
  s.set_step(st.integrated);
  s.set_buffer_size(st.keyframes);
  s.set_phase(st.integrated == 0 ? "waiting" : "mapping");
  s.set_world_size(1);
  status_pub_->Publish(s);
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
    if (mapper_) {
      if (!frame.meta.has_pose()) {
        Count("frames_without_pose");
        return;
      }
      mapper_->Submit(convert::ToSample(frame), camera);
      Count("frames_accepted");
      return;
    }
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
  if (mapper_) {
    closing_ = true;
    mapper_->Stop();  // integrates what is queued and writes a last version (not published)
    const FusionMapper::Stats st = mapper_->GetStats();
    Log().info("mapping stopped: {} frames integrated, {} keyframes, {} dropped while busy, last "
               "version {}", st.integrated, st.keyframes, st.dropped, st.last_version);
    if (mapper_refines_)
      Log().info("refinement fine-tuning stopped: {} rounds, {} steps, last loss {:.4f}",
                 st.refine_rounds, st.refine_steps, st.refine_loss);
    return;
  }
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
