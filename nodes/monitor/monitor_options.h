/// @file monitor_options.h
/// @brief Every parameter of the monitor node in one Options struct: defaults in the field
/// initialisers (written once), read from the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/runtime/parameters.h"

namespace p2i::nodes {

/// The monitor node's configuration (monitor_node.h). A value type: thread-compatible.
struct MonitorOptions {
  double duration = 120.0;  ///< s until the summary; 0 = until stopped
  std::string scene = "builtin:small_office";  ///< ground truth: builtin:NAME or scene YAML
  int camera_width = 640;   ///< the sim camera (as the camera node's default)
  int camera_height = 480;
  std::string lpips_weights;  ///< "" = $P2I_LPIPS_WEIGHTS; missing = LPIPS not scored
  int score_every = 1;        ///< score every N-th view (ground truth costs CPU)
  std::string summary_file;   ///< write the summary JSON here; "" = no file
  std::string sink_summary;   ///< slam_sink summary.json to report from; "" = none
  std::string sequence_dir;   ///< where slam_sink writes (reported)

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static MonitorOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it.
  void Validate() const;
};

}  // namespace p2i::nodes
