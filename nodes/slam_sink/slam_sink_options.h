/// @file slam_sink_options.h
/// @brief Options of the SLAM-augmentation sink (writer, check, policy).
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "nodes/runtime/parameters.h"
#include "nodes/slam_sink/odometry_checker.h"
#include "nodes/slam_sink/tum_sequence_writer.h"

namespace p2i::slam_sink {

/// Flat options of SlamSink. YAML keys (all optional except out_dir): out_dir, append, fsync,
/// write_associations, png_compression, depth_scale, check (bool), policy (flag|drop),
/// write_real, odometry_method, max_translation_error_m, max_rotation_error_deg, min_coverage,
/// min_valid_depth_fraction, min_depth_m, max_depth_m, max_baseline_m, max_baseline_deg.
struct SlamSinkOptions {
  TumSequenceWriterOptions writer;
  OdometryCheckerOptions checker;
  bool check = true;            ///< run the odometry check on synthetic frames
  std::string policy = "flag";  ///< flag: write failing frames, marked; drop: do not write them
  bool write_real = true;       ///< write real frames (when subscribed) interleaved by time

  /// Reads a flat YAML mapping; unknown keys are an error naming the key and `source`.
  static SlamSinkOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// Every parameter of the p2i_slam_sink node (docs/SLAM_SINK.md): the sink's options and the
/// node's topics, calibration file and summary period. Defaults in the field initialisers.
struct SlamSinkNodeOptions {
  SlamSinkOptions sink = SinkDefaults();  ///< out_dir defaults to "slam_sequence" here
  std::string camera_info_file;  ///< ROS camera_info YAML of the views; "" = camera_info_topic
  std::string views_topic = "views";              ///< View topic
  std::string real_topic;                         ///< RgbdFrame topic of real frames; "" = off
  std::string camera_info_topic = "camera_info";  ///< used without camera_info_file
  double summary_period = 5.0;  ///< s between summary.json rewrites; 0 = at exit only

  /// SlamSinkOptions' defaults with the node's output folder.
  static SlamSinkOptions SinkDefaults();
  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static SlamSinkNodeOptions FromParameters(runtime::Parameters& params);
  /// sink.Validate() (which SlamSink's constructor runs too); the node's own fields take any
  /// value (summary_period <= 0: summary.json at exit only).
  void Validate() const { sink.Validate(); }
};

}  // namespace p2i::slam_sink
