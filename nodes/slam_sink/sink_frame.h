/// @file sink_frame.h
/// @brief One RGB-D frame as the SLAM sink receives it: a synthetic view or a real camera frame.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include <opencv2/core.hpp>

#include "scene/pose.h"

namespace p2i::slam_sink {

/// What the sink writes for one received message, decoupled from the wire types so the writer,
/// checker and accounting are testable without sockets. A value type: thread-compatible.
struct SinkFrame {
  double stamp = 0.0;           ///< seconds (capture stamp; for views the requested pose's stamp)
  bool has_pose = true;         ///< false: real frame without a pose (no groundtruth line)
  scene::Pose pose;             ///< camera-to-world: the requested pose for synthetic views
  cv::Mat rgb;                  ///< CV_8UC3, RGB order
  cv::Mat depth;                ///< CV_32FC1 metres, 0 = invalid
  bool synthetic = true;        ///< false: a real camera frame
  std::string source;           ///< publisher / topic name, the key of sequence accounting
  uint64_t seq = 0;             ///< the publisher's message sequence number
  int64_t publish_stamp_ns = 0; ///< when the publisher sent it (0 = unknown); tells restarts apart
  double coverage = std::numeric_limits<double>::quiet_NaN();  ///< NaN = not reported
  std::string method;           ///< synthesis method, for frames.txt (may be empty)
  int64_t model_version = -1;   ///< -1 = unknown
};

}  // namespace p2i::slam_sink
