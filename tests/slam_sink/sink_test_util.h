/// @file sink_test_util.h
/// @brief Helpers of the slam_sink tests: temporary folders, sim-rendered frames, file reading.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "nodes/slam_sink/sink_frame.h"
#include "scene/camera_info.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/temp_dir.h"

namespace p2i::slam_sink::testing {

using p2i::testing::TempDir;

inline scene::CameraInfo SmallCamera(int width = 160, int height = 120) {
  const double f = 0.75 * width;
  return scene::CameraInfo::Pinhole(width, height, f, f, (width - 1) / 2.0, (height - 1) / 2.0,
                                    "sim");
}

inline const scene::SimScene& Office() {
  static const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  return sim;
}

/// A camera in the small office looking at the desk wall: plenty of texture and depth.
inline scene::Pose BasePose() { return scene::LookAt({0.2, -0.4, 1.3}, {-0.6, 2.5, 0.9}); }

/// The pose `base` moved by (dx, dy, dz) in its own camera frame and turned by `yaw_deg` about
/// its own y axis.
inline scene::Pose Moved(const scene::Pose& base, double dx, double dy, double dz,
                         double yaw_deg = 0.0) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  return base * scene::Pose(Eigen::Vector3d(dx, dy, dz), q);
}

/// A synthetic frame rendered at `pose` (exact depth), stamped and numbered.
inline SinkFrame RenderedFrame(const scene::Pose& pose, double stamp, uint64_t seq,
                               const scene::CameraInfo& camera = SmallCamera()) {
  const scene::RgbdSample sample = Office().Render(pose, camera);
  SinkFrame frame;
  frame.stamp = stamp;
  frame.pose = pose;
  frame.rgb = sample.rgb;
  frame.depth = sample.depth;
  frame.synthetic = true;
  frame.source = "/synthesizer";
  frame.seq = seq;
  frame.coverage = 0.9;
  return frame;
}

/// A frame of random colours and random depths in [0.5, 4] m.
inline SinkFrame GarbageFrame(const scene::Pose& pose, double stamp, uint64_t seq,
                              int width = 160, int height = 120) {
  SinkFrame frame;
  frame.stamp = stamp;
  frame.pose = pose;
  frame.rgb = cv::Mat(height, width, CV_8UC3);
  frame.depth = cv::Mat(height, width, CV_32FC1);
  cv::RNG rng(1234 + seq);
  rng.fill(frame.rgb, cv::RNG::UNIFORM, 0, 256);
  rng.fill(frame.depth, cv::RNG::UNIFORM, 0.5, 4.0);
  frame.source = "/synthesizer";
  frame.seq = seq;
  frame.coverage = 0.9;
  return frame;
}

/// Non-comment, non-empty lines of a text file.
inline std::vector<std::string> DataLines(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  return lines;
}

inline std::vector<std::string> Split(const std::string& line) {
  std::istringstream ss(line);
  std::vector<std::string> out;
  std::string token;
  while (ss >> token) out.push_back(token);
  return out;
}

}  // namespace p2i::slam_sink::testing
