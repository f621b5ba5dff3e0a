/// @file procedural_dataset.cc
/// @brief MakeProceduralDataset: an analytic box room for tests and
/// `p2i train --data procedural` while no renderer or dataset is at hand.
#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "model/procedural_dataset.h"

namespace p2i::model {

namespace {

// Room [-2, 2] x [-2, 2] x [0, 3] metres; each wall a colour with stripes and a checker so that
// pose changes move visible structure.
cv::Vec3b WallColour(int wall, const Eigen::Vector3d& p) {
  static const double kBase[6][3] = {{200, 60, 50},  {50, 160, 70},  {60, 80, 200},
                                     {210, 190, 60}, {150, 150, 150}, {230, 230, 230}};
  double u = 0, v = 0;
  switch (wall / 2) {
    case 0: u = p.y(); v = p.z(); break;
    case 1: u = p.x(); v = p.z(); break;
    default: u = p.x(); v = p.y(); break;
  }
  const bool checker = (static_cast<int>(std::floor(u * 2.0)) + static_cast<int>(std::floor(v * 2.0))) % 2 == 0;
  const double stripe = 0.5 + 0.5 * std::sin(u * 5.0 + wall);
  cv::Vec3b c;
  for (int k = 0; k < 3; ++k) {
    double val = kBase[wall][k] * (checker ? 1.0 : 0.55) * (0.75 + 0.25 * stripe);
    c[k] = static_cast<uint8_t>(std::clamp(val, 0.0, 255.0));
  }
  return c;
}

}  // namespace

scene::RgbdDataset MakeProceduralDataset(int num_frames, int size, uint64_t seed) {
  scene::RgbdDataset data;
  const double f = size * 0.8, c = (size - 1) / 2.0;
  data.camera = scene::CameraInfo::Pinhole(size, size, f, f, c, c, "procedural");
  const Eigen::Vector3d lo(-2, -2, 0), hi(2, 2, 3);
  for (int i = 0; i < num_frames; ++i) {
    const double s = static_cast<double>(i) / std::max(1, num_frames) + 0.13 * seed;
    const double yaw = 2.0 * M_PI * s * 0.5;  // half a turn over the sequence
    const Eigen::Vector3d position(0.6 * std::cos(2 * M_PI * s), 0.4 * std::sin(2 * M_PI * s),
                                   1.4 + 0.2 * std::sin(4 * M_PI * s));
    const Eigen::Vector3d forward =
        Eigen::Vector3d(std::cos(yaw), std::sin(yaw), -0.15 + 0.1 * std::cos(2 * M_PI * s))
            .normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d rot;
    rot.col(0) = right;
    rot.col(1) = down;
    rot.col(2) = forward;
    scene::RgbdSample sample;
    sample.pose = scene::Pose(position, Eigen::Quaterniond(rot));
    sample.stamp = i / 30.0;
    sample.id = "procedural/" + std::to_string(i);
    sample.rgb = cv::Mat(size, size, CV_8UC3);
    sample.depth = cv::Mat(size, size, CV_32FC1);
    for (int r = 0; r < size; ++r) {
      for (int col = 0; col < size; ++col) {
        const Eigen::Vector3d ray_cam((col - c) / f, (r - c) / f, 1.0);
        const Eigen::Vector3d d = rot * ray_cam;
        double t_best = 1e9;
        int wall = 0;
        for (int a = 0; a < 3; ++a) {
          if (std::abs(d[a]) < 1e-9) continue;
          const double bound = d[a] > 0 ? hi[a] : lo[a];
          const double t = (bound - position[a]) / d[a];
          if (t > 0 && t < t_best) {
            t_best = t;
            wall = 2 * a + (d[a] > 0 ? 1 : 0);
          }
        }
        const Eigen::Vector3d hit = position + t_best * d;
        sample.rgb.at<cv::Vec3b>(r, col) = WallColour(wall, hit);
        sample.depth.at<float>(r, col) = static_cast<float>(t_best);  // ray_cam.z == 1: z-depth
      }
    }
    data.frames.push_back(std::move(sample));
  }
  return data;
}

}  // namespace p2i::model
