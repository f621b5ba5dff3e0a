/// @file tum_rgbd.h
/// @brief Reader for the TUM RGB-D benchmark layout (rgb.txt, depth.txt, groundtruth.txt).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "scene/dataset_index.h"

namespace p2i::scene {

/// Options of ReadTumRgbd(). Defaults follow the TUM RGB-D benchmark's own tools.
struct TumRgbdOptions {
  DepthEncoding depth{1.0 / 5000.0, 0};
  /// Largest |t_rgb - t_depth| for an rgb and depth image to form a frame (associate.py: 0.02 s).
  double max_difference = 0.02;
  /// Largest gap between the two ground-truth poses a frame's pose is SLERP-ed between; frames
  /// outside the ground truth or in a larger gap are dropped.
  double max_pose_gap = 0.1;
  /// ROS camera_info YAML. Empty = `camera_info.yaml` in the folder if present, else the TUM
  /// "ROS default" calibration (fx = fy = 525, cx = 319.5, cy = 239.5) for 640x480.
  std::string camera_info_file;

  void Validate() const;
};

/// Greedy one-to-one association of two sorted stamp lists as TUM's associate.py does: candidate
/// pairs within max_difference taken in order of increasing |difference|. Returns index pairs
/// (into a, into b) sorted by a's index.
std::vector<std::pair<size_t, size_t>> AssociateStamps(const std::vector<double>& a,
                                                       const std::vector<double>& b,
                                                       double max_difference);

/// Reads a TUM RGB-D sequence folder. A frame's stamp is its rgb stamp; its pose is the ground
/// truth interpolated there. The sequence name is the folder's name; ids are
/// "<sequence>/<rgb stamp as in rgb.txt>". `dropped` (optional) receives how many rgb images got
/// no depth or no pose. Throws std::runtime_error naming the file and line on malformed input,
/// and when no frame remains.
DatasetIndex ReadTumRgbd(const std::string& folder, const TumRgbdOptions& options = {},
                         int* dropped = nullptr);

}  // namespace p2i::scene
