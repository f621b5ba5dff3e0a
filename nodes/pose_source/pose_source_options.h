/// @file pose_source_options.h
/// @brief Every parameter of the pose_source node in one Options struct: defaults in the field
/// initialisers (written once), read from the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/runtime/parameters.h"

namespace p2i::nodes {

/// The pose_source node's configuration (README.md beside this file lists the parameters).
/// A value type: thread-compatible.
struct PoseSourceOptions {
  /// Generator name, inline map "{type: orbit, ...}", generator .yaml file or TUM file
  /// (scene::ResolveTrajectorySpec).
  std::string trajectory = "arm_sweep";
  int trajectory_index = 0;            ///< which one when the spec yields several
  std::string planned_trajectory;      ///< the same kinds of spec for planned poses; "" = none
  int planned_trajectory_index = 0;
  std::string scene = "builtin:small_office";  ///< only for the random_walk generator
  double rate = 20.0;          ///< measured poses per second (> 0)
  double planned_rate = 0.0;   ///< planned poses per second; 0 = rate
  bool loop = true;            ///< start again at the end
  bool exit_at_end = false;    ///< stop the node when a non-looping trajectory ends
  std::string frame_id = "world";

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static PoseSourceOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it.
  void Validate() const;

  /// planned_rate, or rate when it is 0.
  double PlannedRate() const { return planned_rate > 0.0 ? planned_rate : rate; }
};

}  // namespace p2i::nodes
