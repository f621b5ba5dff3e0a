/// @file baseline_warp.cc
/// @brief DIBR forward warping with per-source z-buffers and a z-tolerance blend.
#include "model/baseline_warp.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "model/coverage.h"
#include "model/push_pull_fill.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::model {
namespace {

/// One source frame warped into the output view: front-most depth and colour per pixel.
struct Warped {
  cv::Mat depth;  // CV_32FC1, 0 = nothing landed
  cv::Mat rgb;    // CV_8UC3
};

Warped WarpOne(const scene::RgbdSample& src, const scene::CameraInfo& src_cam,
               const scene::Pose& target, const scene::CameraInfo& out_cam) {
  Warped w;
  w.depth = cv::Mat::zeros(out_cam.image_height, out_cam.image_width, CV_32FC1);
  w.rgb = cv::Mat::zeros(out_cam.image_height, out_cam.image_width, CV_8UC3);
  // Source camera -> target camera transform.
  const Eigen::Matrix4d t_ts = (target.Inverse() * src.pose).ToMatrix();
  const Eigen::Matrix3d r = t_ts.block<3, 3>(0, 0);
  const Eigen::Vector3d t = t_ts.block<3, 1>(0, 3);
  const double sfx = src_cam.fx(), sfy = src_cam.fy(), scx = src_cam.cx(), scy = src_cam.cy();
  const double fx = out_cam.fx(), fy = out_cam.fy(), cx = out_cam.cx(), cy = out_cam.cy();
  const int w_out = out_cam.image_width, h_out = out_cam.image_height;
  for (int v = 0; v < src.depth.rows; ++v) {
    const float* drow = src.depth.ptr<float>(v);
    const cv::Vec3b* crow = src.rgb.ptr<cv::Vec3b>(v);
    for (int u = 0; u < src.depth.cols; ++u) {
      const double z = drow[u];
      if (!(std::isfinite(z) && z > 0.0)) continue;
      const Eigen::Vector3d p_s((u - scx) / sfx * z, (v - scy) / sfy * z, z);
      const Eigen::Vector3d p_t = r * p_s + t;
      if (p_t.z() <= 1e-6) continue;  // behind the target camera
      const int ut = static_cast<int>(std::lround(fx * p_t.x() / p_t.z() + cx));
      const int vt = static_cast<int>(std::lround(fy * p_t.y() / p_t.z() + cy));
      if (ut < 0 || vt < 0 || ut >= w_out || vt >= h_out) continue;
      float& zb = w.depth.at<float>(vt, ut);
      const float zt = static_cast<float>(p_t.z());
      if (zb == 0.0f || zt < zb) {
        zb = zt;
        w.rgb.at<cv::Vec3b>(vt, ut) = crow[u];
      }
    }
  }
  return w;
}

}  // namespace

DepthWarpOptions DepthWarpOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"k", "metres_per_degree", "z_tolerance", "fill_holes"}, "depth_warp options");
  DepthWarpOptions o;
  if (node["k"]) o.k = r.Int(node["k"], "k");
  if (node["metres_per_degree"]) o.metres_per_degree = r.Double(node["metres_per_degree"], "metres_per_degree");
  if (node["z_tolerance"]) o.z_tolerance = r.Double(node["z_tolerance"], "z_tolerance");
  if (node["fill_holes"]) {
    try {
      o.fill_holes = node["fill_holes"].as<bool>();
    } catch (const YAML::Exception&) {
      r.Fail(node["fill_holes"], "fill_holes must be true or false");
    }
  }
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void DepthWarpOptions::Validate() const {
  if (k < 1) throw std::invalid_argument("DepthWarpOptions.k must be >= 1, got " + std::to_string(k));
  if (!std::isfinite(metres_per_degree) || metres_per_degree < 0.0) {
    throw std::invalid_argument("DepthWarpOptions.metres_per_degree must be finite and >= 0");
  }
  if (!std::isfinite(z_tolerance) || z_tolerance < 0.0) {
    throw std::invalid_argument("DepthWarpOptions.z_tolerance must be finite and >= 0");
  }
}

DepthWarp::DepthWarp(scene::RgbdDataset training, DepthWarpOptions options,
                     std::optional<scene::CameraInfo> output_camera)
    : training_(std::move(training)), options_(options) {
  options_.Validate();
  if (training_.frames.empty()) {
    throw std::invalid_argument("DepthWarp: the training dataset has no frames");
  }
  for (const auto& f : training_.frames) {
    scene::CheckFitsCamera(f, training_.camera, "DepthWarp: training frame");
    poses_.push_back(f.pose);
  }
  output_camera_ = output_camera ? *output_camera : training_.camera;
  if (output_camera_.image_width <= 0 || output_camera_.image_height <= 0 ||
      output_camera_.fx() <= 0.0 || output_camera_.fy() <= 0.0) {
    throw std::invalid_argument("DepthWarp: output camera needs a positive size and focal length");
  }
}

scene::RgbdSample DepthWarp::Render(const scene::Pose& pose) {
  const auto nearest =
      NearestPoseIndices(poses_, pose, static_cast<size_t>(options_.k), options_.metres_per_degree);
  std::vector<Warped> warped;
  std::vector<double> weights;
  for (size_t i : nearest) {
    warped.push_back(WarpOne(training_.frames[i], training_.camera, pose, output_camera_));
    weights.push_back(1.0 / (CombinedPoseDistance(pose, poses_[i], options_.metres_per_degree) +
                             1e-3));
  }
  const int h = output_camera_.image_height, w = output_camera_.image_width;
  scene::RgbdSample out;
  out.pose = pose;
  out.id = "depth_warp";
  out.rgb = cv::Mat::zeros(h, w, CV_8UC3);
  out.depth = cv::Mat::zeros(h, w, CV_32FC1);
  cv::Mat holes = cv::Mat::zeros(h, w, CV_8UC1);
  int64_t hole_count = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float z_front = std::numeric_limits<float>::infinity();
      for (const auto& wp : warped) {
        const float z = wp.depth.at<float>(v, u);
        if (z > 0.0f && z < z_front) z_front = z;
      }
      if (!std::isfinite(z_front)) {
        holes.at<uint8_t>(v, u) = 255;
        ++hole_count;
        continue;
      }
      const double limit = z_front * (1.0 + options_.z_tolerance);
      double wsum = 0.0, zsum = 0.0, c[3] = {0.0, 0.0, 0.0};
      for (size_t s = 0; s < warped.size(); ++s) {
        const float z = warped[s].depth.at<float>(v, u);
        if (z <= 0.0f || z > limit) continue;
        const cv::Vec3b& px = warped[s].rgb.at<cv::Vec3b>(v, u);
        wsum += weights[s];
        zsum += weights[s] * z;
        for (int ch = 0; ch < 3; ++ch) c[ch] += weights[s] * px[ch];
      }
      out.depth.at<float>(v, u) = static_cast<float>(zsum / wsum);
      cv::Vec3b& o = out.rgb.at<cv::Vec3b>(v, u);
      for (int ch = 0; ch < 3; ++ch) o[ch] = cv::saturate_cast<uint8_t>(c[ch] / wsum);
    }
  }
  last_hole_fraction_ = static_cast<double>(hole_count) / static_cast<double>(h * w);
  if (options_.fill_holes) PushPullFillRgbd(out.rgb, out.depth, ~holes);
  return out;
}

}  // namespace p2i::model
