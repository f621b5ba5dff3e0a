/// @file rgbd_sample.h
/// @brief One RGB-D frame with its pose: what datasets hold, the trainer learns from and every
/// synthesis method returns.
#pragma once

#include <stdexcept>
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

/// Throws std::invalid_argument "WHAT 'ID' needs rgb CV_8UC3 and depth CV_32FC1 of the camera
/// size WxH" unless `frame`'s images have those types and `camera`'s size. `what` names the caller
/// and the frame's role, e.g. "TsdfVolume::Integrate: frame".
inline void CheckFitsCamera(const RgbdSample& frame, const CameraInfo& camera, const std::string& what) {
  const cv::Size size(camera.image_width, camera.image_height);
  if (frame.rgb.type() != CV_8UC3 || frame.depth.type() != CV_32FC1 || frame.rgb.size() != size ||
      frame.depth.size() != size) {
    throw std::invalid_argument(what + " '" + frame.id + "' needs rgb CV_8UC3 and depth CV_32FC1 of the camera size " +
                                std::to_string(size.width) + "x" + std::to_string(size.height));
  }
}

/// A set of frames of one scene seen by one camera.
struct RgbdDataset {
  CameraInfo camera;
  std::vector<RgbdSample> frames;
};

}  // namespace p2i::scene
