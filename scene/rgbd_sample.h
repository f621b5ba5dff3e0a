/// @file rgbd_sample.h
/// @brief One RGB-D frame with its pose: what datasets hold, the trainer learns from and every
/// synthesis method returns.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "scene/camera_info.h"
#include "scene/pose.h"

namespace p2i::scene {

/// rgb: CV_8UC3 in RGB order (not OpenCV's BGR). depth: CV_32FC1 in metres, 0 = invalid
/// (no measurement or a hole). Both the same size as `camera`.
struct RgbdSample {
  double stamp = 0.0;  ///< seconds
  Pose pose;           ///< camera-to-world
  cv::Mat rgb;
  cv::Mat depth;
  std::string id;      ///< e.g. "seq-01/frame-000935"; for reports
};

/// A set of frames of one scene seen by one camera.
struct RgbdDataset {
  CameraInfo camera;
  std::vector<RgbdSample> frames;
};

}  // namespace p2i::scene
