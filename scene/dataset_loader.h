/// @file dataset_loader.h
/// @brief Opens any supported dataset folder (p2i capture, TUM RGB-D, 7-Scenes) by its layout.
#pragma once

#include <string>

#include "scene/dataset_index.h"

namespace p2i::scene {

/// Options of OpenDataset(). A value type.
struct DatasetOptions {
  /// "auto", "capture", "tum" or "7scenes".
  std::string format = "auto";
  /// 7-Scenes only: the raw depth value meaning "no depth" (7-Scenes 65535; study-room data 0).
  int seven_scenes_invalid_depth = 65535;
  /// TUM only: association window in seconds.
  double tum_max_difference = 0.02;
  /// TUM only: largest ground-truth gap a pose is interpolated across, seconds.
  double tum_max_pose_gap = 0.1;
  /// Overrides the calibration found in the folder (ROS camera_info YAML); empty = none.
  std::string camera_info_file;

  void Validate() const;
};

/// The layout detected at `path`: "capture" (manifest.yaml, or sub-folders that are captures,
/// e.g. what `p2i render` writes: seq-01/, seq-02/), "tum" (rgb.txt + depth.txt, or sub-folders
/// that are TUM sequences), "7scenes" (seq-*/frame-*.pose.txt or frame-*.pose.txt), or "" when
/// none matches.
std::string DetectDatasetFormat(const std::string& path);

/// Opens the dataset at `path` (format from options or detected). Several sub-folder sequences
/// are concatenated in name order; they must share one calibration. Throws std::runtime_error
/// naming the path and what was expected when nothing matches.
DatasetIndex OpenDataset(const std::string& path, const DatasetOptions& options = {});

}  // namespace p2i::scene
