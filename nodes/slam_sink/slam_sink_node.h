/// @file slam_sink_node.h
/// @brief p2i_slam_sink: writes received synthetic views (and optionally real frames) as a TUM
/// RGB-D sequence, checking each view with RGB-D odometry (see docs/SLAM_SINK.md).
#pragma once

#include <memory>
#include <string>

#include "nodes/runtime/node.h"
#include "nodes/slam_sink/slam_sink.h"

namespace p2i::slam_sink {

/// Parameters (SlamSinkNodeOptions, slam_sink_options.h): out_dir, append, fsync,
/// png_compression, write_associations, check, policy (flag|drop), write_real, odometry_method, max_translation_error_m, max_rotation_error_deg,
/// min_coverage, min_valid_depth_fraction, min_depth_m, max_depth_m, max_baseline_m,
/// max_baseline_deg, camera_info_file (ROS YAML of the views' camera; else the first message on
/// camera_info_topic), views_topic ("views"), real_topic ("" = off), camera_info_topic
/// ("camera_info", "" = off), summary_period (s, 0 = only at shutdown).
/// Topics: subscribes views_topic (View), real_topic (RgbdFrame), camera_info_topic (CameraInfo).
/// Counters: views_received, real_received, frames_written, check_failed, dropped, seq_missing,
/// bad_frames, write_errors; values: pass_rate, odom_t_err_median_m, odom_r_err_median_deg.
/// On SIGINT/SIGTERM: finalises the sequence, writes summary.json and logs the summary.
/// Thread-safety: everything runs on the node's executor thread.
class SlamSinkNode : public runtime::Node {
 public:
  explicit SlamSinkNode(const runtime::NodeArgs& args);

 protected:
  void OnShutdown() override;

 private:
  // Start-up steps of the constructor, after the parameters.
  void SubscribeViews(const std::string& topic);       // synthetic views -> OnFrame
  void SubscribeRealFrames(const std::string& topic);  // real RGB-D frames -> OnFrame
  void SubscribeCameraInfo(const std::string& topic);  // enables the check once calibrated
  void StartSummaryTimer(double period_s);             // rewrites summary.json periodically

  void OnFrame(const SinkFrame& frame);
  void UpdateStatus();

  std::unique_ptr<SlamSink> sink_;
  std::shared_ptr<runtime::RawSubscriber> views_sub_;
  std::shared_ptr<runtime::RawSubscriber> real_sub_;
  std::shared_ptr<runtime::RawSubscriber> camera_sub_;
};

}  // namespace p2i::slam_sink
