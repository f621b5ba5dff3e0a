/// @file dataset_index.h
/// @brief A dataset as a list of frame references (paths + poses), with pixels loaded on demand.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::scene {

/// How a 16-bit depth PNG maps to metres: metres = raw * scale; `invalid_value` (and always 0)
/// mean "no measurement". 7-Scenes: scale 0.001, invalid 65535. TUM RGB-D: scale 1/5000,
/// invalid 0. p2i capture and the study-room data: scale 0.001, invalid 0.
struct DepthEncoding {
  double scale = 0.001;
  uint16_t invalid_value = 0;
};

/// One frame of a dataset before its pixels are read.
struct FrameRef {
  std::string id;        ///< unique in the dataset, e.g. "seq-01/frame-000935"
  std::string sequence;  ///< the trajectory it belongs to, e.g. "seq-01" ("" when only one)
  double stamp = 0.0;    ///< seconds
  Pose pose;             ///< camera-to-world
  std::string rgb_path;
  std::string depth_path;
};

/// Reads an 8-bit colour PNG/JPEG and returns it as CV_8UC3 in RGB order. Grey images are
/// expanded to three channels. Throws std::runtime_error naming the file when it cannot be read.
cv::Mat ReadRgbImage(const std::string& path);
/// Reads a 16-bit single-channel depth PNG and returns CV_32FC1 metres with 0 = invalid.
/// Throws std::runtime_error naming the file when it is missing or not 16-bit single-channel.
cv::Mat ReadDepthImage(const std::string& path, const DepthEncoding& encoding);
/// Converts CV_32FC1 metres (0 or non-finite = invalid) to CV_16UC1 millimetres with 0 invalid;
/// depths beyond 65.534 m become invalid.
cv::Mat DepthToMillimetres(const cv::Mat& depth_m);

/// Frames (paths + poses) of one or several trajectories seen by one camera. Pixels are read by
/// Load(), so a long sequence costs only its pose list until frames are used. A value type:
/// thread-compatible; Load() is const and may be called from several threads at once.
class DatasetIndex {
 public:
  DatasetIndex() = default;
  DatasetIndex(CameraInfo camera, DepthEncoding encoding, std::vector<FrameRef> frames);

  const CameraInfo& camera() const { return camera_; }
  const DepthEncoding& depth_encoding() const { return encoding_; }
  const std::vector<FrameRef>& frames() const { return frames_; }
  size_t size() const { return frames_.size(); }
  bool empty() const { return frames_.empty(); }

  /// Reads frame i. Throws std::out_of_range for a bad index, std::runtime_error naming the file
  /// when an image is unreadable or its size differs from camera().
  RgbdSample Load(size_t i) const;
  /// Reads every frame into memory.
  RgbdDataset LoadAll() const;

  /// Sequence names in order of first appearance.
  std::vector<std::string> Sequences() const;
  /// The frames of the given sequences (in dataset order), same camera and encoding.
  DatasetIndex SelectSequences(const std::vector<std::string>& sequences) const;
  /// The frames with these ids, in the order given. Throws std::invalid_argument naming the
  /// first id not in the dataset.
  DatasetIndex SelectIds(const std::vector<std::string>& ids) const;
  /// Index of the frame with this id, or -1.
  int Find(const std::string& id) const;

 private:
  CameraInfo camera_;
  DepthEncoding encoding_;
  std::vector<FrameRef> frames_;
};

}  // namespace p2i::scene
