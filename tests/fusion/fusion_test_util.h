/// @file fusion_test_util.h
/// @brief Analytic RGB-D frames for the fusion tests: a textured world plane z = plane_z (and an
/// optional closer square patch), rendered exactly at any pose.
#pragma once

#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "fusion/fusion_scene.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::fusion::testing {

/// A fronto-parallel scene: the plane z = plane_z (world), and when patch_z is set a square
/// |x|, |y| <= patch_half at z = patch_z in front of it. Colour: a smooth texture of (x, y) with a
/// different tint on the patch, so a wrong source pixel shows.
struct PlaneScene {
  double plane_z = 2.0;
  std::optional<double> patch_z;
  double patch_half = 0.2;
  /// Angular frequency (rad/m) of the plane texture's first term: 9 by default (a smooth texture);
  /// higher gives detail a few pixels wide, which shows misregistration between keyframes.
  double detail = 9.0;

  cv::Vec3b Colour(double x, double y, bool patch) const {
    const double a = 0.5 + 0.5 * std::sin(detail * x) * std::cos(7.0 / 9.0 * detail * y);
    const double b = 0.5 + 0.5 * std::cos(5.0 * x + 3.0 * y);
    if (patch) return cv::Vec3b(static_cast<uint8_t>(40 + 60 * b), static_cast<uint8_t>(200 * a),
                                static_cast<uint8_t>(230));
    return cv::Vec3b(static_cast<uint8_t>(30 + 200 * a), static_cast<uint8_t>(30 + 200 * b),
                     static_cast<uint8_t>(60 + 100 * a * b));
  }

  /// Exact render (pose camera-to-world, camera axes x right, y down, z forward).
  scene::RgbdSample Render(const scene::Pose& pose, const scene::CameraInfo& cam) const {
    scene::RgbdSample s;
    s.pose = pose;
    s.rgb = cv::Mat::zeros(cam.image_height, cam.image_width, CV_8UC3);
    s.depth = cv::Mat::zeros(cam.image_height, cam.image_width, CV_32FC1);
    const Eigen::Matrix3d r = pose.rotation().toRotationMatrix();
    const Eigen::Vector3d c = pose.translation();
    for (int v = 0; v < cam.image_height; ++v) {
      for (int u = 0; u < cam.image_width; ++u) {
        const Eigen::Vector3d d_cam((u - cam.cx()) / cam.fx(), (v - cam.cy()) / cam.fy(), 1.0);
        const Eigen::Vector3d d = r * d_cam;
        if (std::abs(d.z()) < 1e-9) continue;
        double t = (plane_z - c.z()) / d.z();
        bool on_patch = false;
        if (patch_z) {
          const double tp = (*patch_z - c.z()) / d.z();
          const Eigen::Vector3d x = c + tp * d;
          if (tp > 0 && std::abs(x.x()) <= patch_half && std::abs(x.y()) <= patch_half) {
            t = tp;
            on_patch = true;
          }
        }
        if (t <= 0) continue;
        const Eigen::Vector3d x = c + t * d;
        s.depth.at<float>(v, u) = static_cast<float>(t);  // d_cam.z == 1: t is the z-depth
        s.rgb.at<cv::Vec3b>(v, u) = Colour(x.x(), x.y(), on_patch);
      }
    }
    return s;
  }
};

inline scene::Pose At(double x, double y, double z) {
  return scene::Pose(Eigen::Vector3d(x, y, z), Eigen::Quaterniond::Identity());
}

inline scene::CameraInfo Cam(int w, int h, double f) {
  return scene::CameraInfo::Pinhole(w, h, f, f, (w - 1) / 2.0, (h - 1) / 2.0);
}

/// Keyframes at (x, 0, 0) for each x in `xs`, their colour and depth exact, over a TSDF that fused
/// their depth `scale` x too deep, as a depth sensor's bias does. Each keyframe then projects its
/// colour onto a surface that is off, so the slots of a view land their detail at pixels that
/// differ with their baselines (parallax) and the blend doubles it, around the right place. The
/// slots colour that surface only when the visibility tolerance covers the error.
inline void AddOverScaledGeometry(const PlaneScene& scene, const scene::CameraInfo& cam,
                                  const std::vector<double>& xs, double scale, FusionScene* fs) {
  for (double x : xs) {
    const scene::RgbdSample truth = scene.Render(At(x, 0, 0), cam);
    scene::RgbdSample fused = truth;
    const cv::Mat deeper = truth.depth * scale;  // a new buffer: fused shares truth's
    fused.depth = deeper;
    fs->Integrate(fused);
    fs->AddFrame(truth, /*integrate=*/false);
  }
}

}  // namespace p2i::fusion::testing
