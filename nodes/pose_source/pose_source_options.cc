/// @file pose_source_options.cc
/// @brief The pose_source node's parameters -> PoseSourceOptions, and their validation.
#include "nodes/pose_source/pose_source_options.h"

#include "nodes/runtime/option_error.h"

namespace p2i::nodes {

PoseSourceOptions PoseSourceOptions::FromParameters(runtime::Parameters& p) {
  PoseSourceOptions o;  // the defaults, written once in the field initialisers
  o.trajectory = p.Declare<std::string>(
      "trajectory", o.trajectory, "generator name, inline {type: ...} map, .yaml or TUM file");
  o.trajectory_index =
      p.Declare<int>("trajectory_index", o.trajectory_index, "which trajectory of a multi spec");
  o.planned_trajectory = p.Declare<std::string>("planned_trajectory", o.planned_trajectory,
                                                "spec of planned poses; empty = none");
  o.planned_trajectory_index = p.Declare<int>("planned_trajectory_index",
                                              o.planned_trajectory_index, "which planned one");
  o.scene = p.Declare<std::string>("scene", o.scene, "scene for the random_walk generator");
  o.rate = p.Declare<double>("rate", o.rate, "measured poses per second");
  o.planned_rate =
      p.Declare<double>("planned_rate", o.planned_rate, "planned poses per second; 0 = rate");
  o.loop = p.Declare<bool>("loop", o.loop, "restart the trajectory at its end");
  o.exit_at_end =
      p.Declare<bool>("exit_at_end", o.exit_at_end, "stop the node when the trajectory ends");
  o.frame_id = p.Declare<std::string>("frame_id", o.frame_id, "frame of the poses");
  return o;
}

void PoseSourceOptions::Validate() const {
  using runtime::CheckOption;
  CheckOption(!trajectory.empty(), "pose_source", "trajectory", trajectory,
              "name a trajectory spec", "e.g. trajectory:=orbit");
  CheckOption(trajectory_index >= 0, "pose_source", "trajectory_index", trajectory_index,
              "be >= 0", "0 = the first trajectory of the spec");
  CheckOption(planned_trajectory_index >= 0, "pose_source", "planned_trajectory_index",
              planned_trajectory_index, "be >= 0", "0 = the first trajectory of the spec");
  CheckOption(rate > 0.0, "pose_source", "rate", rate, "be > 0",
              "poses per second, e.g. rate:=20");
  CheckOption(planned_rate >= 0.0, "pose_source", "planned_rate", planned_rate, "be >= 0",
              "planned_rate:=0 publishes planned poses at `rate`");
}

}  // namespace p2i::nodes
