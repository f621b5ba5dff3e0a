/// @file sim_source.h
/// @brief backend:=sim: the synthetic scene rendered at the newest pose received on "pose"
/// (at most `rate` frames/s, capture stamp = the pose's) or along its own trajectory.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "nodes/camera/camera_options.h"
#include "nodes/camera/frame_source.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

/// Counters: laps (trajectory mode), poses_skipped (topic mode: poses replaced before they were
/// rendered). Thread-safety: FrameSource's.
class SimSource : public FrameSource {
 public:
  /// Loads the scene, the calibration and (pose_mode trajectory) the trajectory; throws
  /// runtime::StartupError naming what is wrong. `options` must have passed Validate().
  explicit SimSource(const SimSourceOptions& options);

  const scene::CameraInfo& camera() const override { return camera_; }
  void Start(runtime::Node& node, Emit emit) override;

 private:
  void OnTick();

  SimSourceOptions options_;
  std::optional<scene::SimScene> sim_;
  scene::CameraInfo camera_;
  std::vector<scene::StampedPose> trajectory_;  ///< empty with pose_mode topic
  runtime::Node* node_ = nullptr;
  Emit emit_;
  std::shared_ptr<runtime::RawSubscriber> pose_sub_;
  size_t trajectory_index_ = 0;
  std::optional<scene::Pose> pending_pose_;  ///< newest pose from the topic, not yet rendered
  int64_t pending_stamp_ns_ = 0;
  bool finished_ = false;
};

}  // namespace p2i::nodes
