/// @file camera_node.h
/// @brief The camera node: RGB-D frames with intrinsics and poses from a backend chosen by
/// parameter: `sim` (the synthetic scene) or `replay` (a dataset folder).
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nodes/runtime/node.h"
#include "scene/dataset_index.h"
#include "scene/pose.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

/// Parameters (README.md beside this file has the full list):
///   backend: "sim" | "replay";
///   rate (Hz): sim frames per second (20); replay: 0 = the recorded rate;
///   width, height (0 = native): sim render size; replay centre-crop + resize;
///   camera_info_file: ROS camera_info YAML (sim; replay: override);
///   sim: scene ("builtin:small_office" or a YAML file), kinect (bool), pose_mode ("topic":
///     render at the newest pose received on "pose", at most `rate` per second; "trajectory":
///     its own trajectory spec), trajectory, trajectory_index, loop;
///   replay: dataset (folder), format, invalid_depth (7-Scenes raw value), rate_scale (1.0),
///     loop (false), exit_at_end (false).
/// Topics: publishes "rgbd" (RgbdFrame with the full camera_info and the pose) and
/// "camera_info" (CameraInfo, latched); sim in topic mode subscribes "pose" (PoseStamped).
/// Counters: frames_published, frames_skipped (replay fell behind), laps.
/// Thread-safety: everything runs on the node's executor thread.
class CameraNode : public runtime::Node {
 public:
  explicit CameraNode(const runtime::NodeArgs& args);

 private:
  void SetUpSim();
  void SetUpReplay();
  void PublishSample(const scene::RgbdSample& sample, int64_t capture_stamp_ns);
  void OnSimTick();
  void OnReplayTick();

  std::string frame_id_;
  scene::CameraInfo camera_;
  std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>> rgbd_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::CameraInfo>> info_pub_;
  std::shared_ptr<runtime::RawSubscriber> pose_sub_;
  double rate_ = 20.0;
  bool loop_ = false;
  bool exit_at_end_ = false;

  // sim
  std::optional<scene::SimScene> sim_;
  std::vector<scene::StampedPose> trajectory_;
  size_t trajectory_index_ = 0;
  std::optional<scene::Pose> pending_pose_;  ///< newest pose from the topic, not yet rendered
  int64_t pending_stamp_ns_ = 0;

  // replay
  scene::DatasetIndex dataset_;
  int out_width_ = 0, out_height_ = 0;
  double rate_scale_ = 1.0;
  size_t next_frame_ = 0;
  std::chrono::steady_clock::time_point lap_start_;
  bool finished_ = false;
};

}  // namespace p2i::nodes
