/// @file sim_source.cc
/// @brief SimSource: the sim scene rendered at topic poses or along a trajectory.
#include "nodes/camera/sim_source.h"

#include <chrono>

#include "convert/pose.h"
#include "scene/dataset_trajectories.h"

namespace p2i::nodes {

SimSource::SimSource(const SimSourceOptions& options) : options_(options) {
  const SimSourceOptions& o = options_;
  try {
    sim_.emplace(scene::SimScene::FromSpec(o.scene));
    if (o.kinect) sim_->set_sensor_options(scene::SimSensorOptions::Kinect());
    if (!o.camera_info_file.empty()) {
      camera_ = scene::CameraInfo::FromYamlFile(o.camera_info_file);
      if (o.width > 0 && o.height > 0) camera_ = camera_.Scaled(o.width, o.height);
    } else {
      camera_ = scene::SimScene::DefaultCamera(o.width > 0 ? o.width : 640,
                                               o.height > 0 ? o.height : 480);
    }
    if (o.pose_mode == "trajectory") {
      auto all = scene::ResolveTrajectorySpec(o.trajectory, &*sim_);
      if (static_cast<size_t>(o.trajectory_index) >= all.size()) {
        throw runtime::StartupError("trajectory_index out of range for '" + o.trajectory + "'");
      }
      trajectory_ = std::move(all[o.trajectory_index]);
    }
  } catch (const runtime::StartupError&) {
    throw;
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
}

void SimSource::Start(runtime::Node& node, Emit emit) {
  node_ = &node;
  emit_ = std::move(emit);
  const bool topic = options_.pose_mode == "topic";
  if (topic) {
    runtime::SubscriberOptions latest;
    latest.latest_only = true;
    pose_sub_ = node.Subscribe<msgs::pb::PoseStamped>(
        "pose",
        [this](const msgs::pb::PoseStamped& msg) {
          if (pending_pose_) node_->Count("poses_skipped");
          pending_pose_ = convert::FromMsg(msg.pose());
          pending_stamp_ns_ = msg.header().capture_stamp_ns();
        },
        latest);
  }
  node.Log().info("sim backend: {} at {}x{}, {} Hz, poses from {}", options_.scene,
                  camera_.image_width, camera_.image_height, options_.rate,
                  topic ? "topic " + node.Resolve("pose")
                        : "trajectory '" + options_.trajectory + "'");
  node.AddTimer(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / options_.rate)),
                [this] { OnTick(); });
}

void SimSource::OnTick() {
  if (finished_) return;
  scene::Pose pose;
  int64_t stamp = 0;
  if (trajectory_.empty()) {
    if (!pending_pose_) return;
    pose = *pending_pose_;
    stamp = pending_stamp_ns_;
    pending_pose_.reset();
  } else {
    pose = trajectory_[trajectory_index_].pose;
    stamp = runtime::NowNs();
    if (++trajectory_index_ >= trajectory_.size()) {
      trajectory_index_ = 0;
      node_->Count("laps");
      if (!options_.loop) {
        finished_ = true;
        if (options_.exit_at_end) node_->Stop();
      }
    }
  }
  const scene::RgbdSample sample = sim_->Render(pose, camera_, static_cast<double>(stamp) * 1e-9);
  emit_(sample.rgb, sample.depth, &sample.pose, stamp);
}

}  // namespace p2i::nodes
