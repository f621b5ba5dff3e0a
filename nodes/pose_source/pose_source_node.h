/// @file pose_source_node.h
/// @brief The pose_source node: publishes measured poses (what the robot reports while
/// capturing) and planned poses (requests for synthetic views) at a rate.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nodes/pose_source/pose_source_options.h"
#include "nodes/runtime/node.h"
#include "scene/pose.h"

namespace p2i::nodes {

/// Parameters: PoseSourceOptions (pose_source_options.h; README.md beside this file lists
/// them): trajectory, trajectory_index, planned_trajectory, planned_trajectory_index, scene,
/// rate, planned_rate, loop, exit_at_end, frame_id.
/// Topics: "pose" (PoseStamped; capture stamp = publish time), "planned_pose" (PoseRequest with
/// increasing request_id). Counters: poses_published, planned_published, laps.
/// Thread-safety: everything runs on the node's executor thread.
class PoseSourceNode : public runtime::Node {
 public:
  explicit PoseSourceNode(const runtime::NodeArgs& args);

 private:
  void PublishMeasured();
  void PublishPlanned();
  bool Advance(size_t* index, size_t size);

  std::vector<scene::StampedPose> measured_;
  std::vector<scene::StampedPose> planned_;
  size_t measured_index_ = 0;
  size_t planned_index_ = 0;
  uint64_t request_id_ = 0;
  bool loop_ = true;
  bool exit_at_end_ = false;
  bool measured_done_ = false;
  bool planned_done_ = false;
  std::string frame_id_;
  std::shared_ptr<runtime::Publisher<msgs::pb::PoseStamped>> pose_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::PoseRequest>> planned_pub_;
};

}  // namespace p2i::nodes
