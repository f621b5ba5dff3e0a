/// @file dataset_test_util.h
/// @brief Helpers for the dataset tests: temporary folders and small synthetic frames.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::testing {

/// A fresh folder under $TMPDIR, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() {
    std::string templ = (std::filesystem::temp_directory_path() / "p2i_data_XXXXXX").string();
    path_ = mkdtemp(templ.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

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
