/// @file slam_sink_options.h
/// @brief Options of the SLAM-augmentation sink (writer, check, policy).
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

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

}  // namespace p2i::slam_sink
