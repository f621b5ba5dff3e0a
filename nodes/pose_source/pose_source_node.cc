/// @file pose_source_node.cc
/// @brief pose_source: trajectories from generators or files, published at a rate.
#include "nodes/pose_source/pose_source_node.h"

#include <chrono>
#include <optional>

#include "convert/pose.h"
#include "scene/dataset_trajectories.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {
namespace {

std::chrono::nanoseconds Period(double rate_hz) {
  return std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate_hz));
}

std::vector<scene::StampedPose> LoadOne(const std::string& spec, int index,
                                        const std::string& scene_spec, const char* param) {
  std::optional<scene::SimScene> sim;
  if (spec.find("random_walk") != std::string::npos) sim.emplace(scene::SimScene::FromSpec(scene_spec));
  auto all = scene::ResolveTrajectorySpec(spec, sim ? &*sim : nullptr);
  if (index < 0 || static_cast<size_t>(index) >= all.size()) {
    throw runtime::StartupError(std::string(param) + "_index " + std::to_string(index) +
                                " is out of range: '" + spec + "' gives " +
                                std::to_string(all.size()) + " trajectories");
  }
  if (all[index].empty()) throw runtime::StartupError("trajectory '" + spec + "' is empty");
  return all[index];
}

}  // namespace

PoseSourceNode::PoseSourceNode(const runtime::NodeArgs& args) : Node("pose_source", args) {
  const PoseSourceOptions o = PoseSourceOptions::FromParameters(Params());
  o.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  loop_ = o.loop;
  exit_at_end_ = o.exit_at_end;
  frame_id_ = o.frame_id;
  const std::string& spec = o.trajectory;
  const std::string& planned_spec = o.planned_trajectory;
  const double rate = o.rate;
  const double planned_rate = o.PlannedRate();
  ParametersDone();

  try {
    measured_ = LoadOne(spec, o.trajectory_index, o.scene, "trajectory");
    if (!planned_spec.empty()) {
      planned_ = LoadOne(planned_spec, o.planned_trajectory_index, o.scene,
                         "planned_trajectory");
    }
  } catch (const runtime::StartupError&) {
    throw;
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  Log().info("{} measured poses at {} Hz from '{}'{}", measured_.size(), rate, spec,
             planned_.empty() ? std::string()
                              : ", " + std::to_string(planned_.size()) + " planned poses from '" +
                                    planned_spec + "'");

  pose_pub_ = Advertise<msgs::pb::PoseStamped>("pose");
  AddTimer(Period(rate), [this] { PublishMeasured(); });
  if (!planned_.empty()) {
    planned_pub_ = Advertise<msgs::pb::PoseRequest>("planned_pose");
    AddTimer(Period(planned_rate), [this] { PublishPlanned(); });
  } else {
    planned_done_ = true;
  }
}

bool PoseSourceNode::Advance(size_t* index, size_t size) {
  if (++*index < size) return true;
  if (!loop_) return false;
  *index = 0;
  Count("laps");
  return true;
}

void PoseSourceNode::PublishMeasured() {
  if (measured_done_) return;
  msgs::pb::PoseStamped msg;
  msg.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
  msg.mutable_header()->set_frame_id(frame_id_);
  convert::ToMsg(measured_[measured_index_].pose, msg.mutable_pose(), frame_id_);
  pose_pub_->Publish(msg);
  Count("poses_published");
  if (!Advance(&measured_index_, measured_.size())) {
    measured_done_ = true;
    Log().info("measured trajectory finished ({} poses)", measured_.size());
    if (exit_at_end_ && planned_done_) Stop();
  }
}

void PoseSourceNode::PublishPlanned() {
  if (planned_done_) return;
  msgs::pb::PoseRequest msg;
  msg.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
  msg.mutable_header()->set_frame_id(frame_id_);
  msg.set_request_id(++request_id_);
  convert::ToMsg(planned_[planned_index_].pose, msg.mutable_pose(), frame_id_);
  planned_pub_->Publish(msg);
  Count("planned_published");
  if (!Advance(&planned_index_, planned_.size())) {
    planned_done_ = true;
    Log().info("planned trajectory finished ({} poses)", planned_.size());
    if (exit_at_end_ && measured_done_) Stop();
  }
}

}  // namespace p2i::nodes
