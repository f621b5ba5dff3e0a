/// @file seven_scenes.h
/// @brief Reader for the Microsoft 7-Scenes layout (and 7-Scenes-like folders such as the
/// study-room data in ../shared/data).
#pragma once

#include <string>
#include <vector>

#include "scene/dataset_index.h"

namespace p2i::scene {

/// Options of ReadSevenScenes(). Defaults are those of 7-Scenes itself.
struct SevenScenesOptions {
  /// 7-Scenes marks missing depth with 65535; the study-room data uses 0 (0 is always invalid).
  DepthEncoding depth{0.001, 65535};
  /// 7-Scenes has no timestamps: stamp = frame number / frame_rate (Kinect: 30 Hz).
  double frame_rate = 30.0;
  /// Sequence folders to read (e.g. {"seq-01"}); empty = every seq-* folder, sorted.
  std::vector<std::string> sequences;
  /// Calibration file (ROS camera_info YAML). Empty = `camera_info.yaml` in the root if present,
  /// else `camera-intrinsics.txt` (3x3 K) if present, else 7-Scenes' f = 585, c = (320, 240).
  std::string camera_info_file;

  /// Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Reads the frame list of `root`, which is either a scene folder holding seq-XX/ folders or one
/// seq-XX folder holding frame-NNNNNN.{color.png,depth.png,pose.txt}. Poses (4x4 camera-to-world
/// matrices) are read now, pixels on DatasetIndex::Load(). Ids are "seq-XX/frame-NNNNNN";
/// sequence is "seq-XX". Throws std::runtime_error naming the file and the problem (missing
/// folder, no frames, a frame missing its colour/depth/pose file, a malformed pose).
DatasetIndex ReadSevenScenes(const std::string& root, const SevenScenesOptions& options = {});

/// Parses a 7-Scenes pose file (4 rows of 4 numbers). Throws std::runtime_error naming the file.
Pose ReadSevenScenesPose(const std::string& path);

/// Parses a 3x3 intrinsics matrix file (camera-intrinsics.txt) for an image of width x height.
CameraInfo ReadIntrinsicsMatrixFile(const std::string& path, int width, int height);

}  // namespace p2i::scene
