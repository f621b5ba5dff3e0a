/// @file monitor_options.cc
/// @brief The monitor node's parameters -> MonitorOptions, and their validation.
#include "nodes/monitor/monitor_options.h"

#include "nodes/runtime/option_error.h"

namespace p2i::nodes {

MonitorOptions MonitorOptions::FromParameters(runtime::Parameters& p) {
  MonitorOptions o;  // the defaults, written once in the field initialisers
  o.duration = p.Declare<double>("duration", o.duration,
                                 "seconds until the summary; 0 = until stopped");
  o.scene =
      p.Declare<std::string>("scene", o.scene, "ground truth: builtin:NAME or YAML");
  o.camera_width = p.Declare<int>("camera_width", o.camera_width,
                                  "sim camera width (as the camera node)");
  o.camera_height = p.Declare<int>("camera_height", o.camera_height,
                                   "sim camera height (as the camera node)");
  o.lpips_weights = p.Declare<std::string>(
      "lpips_weights", o.lpips_weights,
      "LPIPS-Squeeze weights; '' = $P2I_LPIPS_WEIGHTS; missing = not scored");
  o.score_every = p.Declare<int>("score_every", o.score_every,
                                 "score every N-th view (ground truth costs CPU)");
  o.summary_file =
      p.Declare<std::string>("summary_file", o.summary_file, "write the summary JSON here");
  o.sink_summary =
      p.Declare<std::string>("sink_summary", o.sink_summary, "slam_sink summary.json to report from");
  o.sequence_dir = p.Declare<std::string>("sequence_dir", o.sequence_dir,
                                          "where slam_sink writes (reported)");
  return o;
}

void MonitorOptions::Validate() const {
  using runtime::CheckOption;
  CheckOption(duration >= 0.0, "monitor", "duration", duration, "be >= 0",
              "seconds; duration:=0 runs until stopped");
  CheckOption(camera_width > 0, "monitor", "camera_width", camera_width, "be > 0",
              "the camera node's width, e.g. camera_width:=640");
  CheckOption(camera_height > 0, "monitor", "camera_height", camera_height, "be > 0",
              "the camera node's height, e.g. camera_height:=480");
  CheckOption(score_every >= 1, "monitor", "score_every", score_every, "be >= 1",
              "score_every:=1 scores every view");
}

}  // namespace p2i::nodes
