/// @file dataset_test_util.h
/// @brief Helpers for the dataset tests: small synthetic frames (temporary folders:
/// tests/temp_dir.h).
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "tests/temp_dir.h"

namespace p2i::testing {

/// RGB with a different value per channel and per pixel (so a BGR/RGB swap or a transpose shows)
/// and depth in whole millimetres with a few invalid (0) pixels.
inline scene::RgbdSample MakeSample(int width, int height, int seed, double stamp,
                                    const scene::Pose& pose) {
  scene::RgbdSample s;
  s.stamp = stamp;
  s.pose = pose;
  s.id = "synthetic-" + std::to_string(seed);
  s.rgb.create(height, width, CV_8UC3);
  s.depth.create(height, width, CV_32FC1);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      s.rgb.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>((10 * c + seed) % 256),
                                             static_cast<uchar>((7 * r + 3 * seed) % 256), 200);
      const bool hole = (r * width + c + seed) % 17 == 0;
      s.depth.at<float>(r, c) = hole ? 0.0f : static_cast<float>(500 + r * 10 + c + seed) / 1000.f;
    }
  }
  return s;
}

inline scene::Pose MakePose(double x, double yaw_deg) {
  const double a = yaw_deg * M_PI / 180.0;
  return scene::Pose(Eigen::Vector3d(x, 0.1 * x, 1.5),
                     Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY())));
}

}  // namespace p2i::testing
