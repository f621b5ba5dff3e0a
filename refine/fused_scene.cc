/// @file fused_scene.cc
/// @brief MakeFusedScene: an Open3D VoxelBlockGrid TSDF (integrate, raycast) plus keyframe
/// candidates (nearest keyframes by pose, depth-test visibility, angle-based blend weights).
///
/// Stopgap: this is the refinement's own minimal fused scene, written while the fusion
/// geometry/appearance code (fusion/, issue 12 points 1-2) had not landed; it fills the same
/// fusion::ViewCandidates layout. Switch MakeFusedScene to the fusion code when it is on main.
#include "refine/fused_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <open3d/core/Tensor.h>
#include <open3d/t/geometry/Image.h>
#include <open3d/t/geometry/VoxelBlockGrid.h>
#include <opencv2/imgproc.hpp>

#include "model/coverage.h"

namespace p2i::refine {

namespace o3c = open3d::core;
namespace o3g = open3d::t::geometry;

void FusedSceneOptions::Validate() const {
  if (!(voxel_size_m > 0.002 && voxel_size_m < 1.0))
    throw std::invalid_argument("FusedSceneOptions: voxel_size_m must be in (0.002, 1) m");
  if (sdf_trunc_m < 0) throw std::invalid_argument("FusedSceneOptions: sdf_trunc_m must be >= 0");
  if (!(depth_max_m > 0)) throw std::invalid_argument("FusedSceneOptions: depth_max_m must be > 0");
  if (k < 1 || k > 8) throw std::invalid_argument("FusedSceneOptions: k must be in [1, 8]");
}

namespace {

constexpr double kAngleSigmaDeg = 10.0;

o3c::Tensor Intrinsic(const scene::CameraInfo& c) {
  const auto& K = c.camera_matrix;
  return o3c::Tensor(std::vector<double>{K[0], 0, K[2], 0, K[4], K[5], 0, 0, 1}, {3, 3},
                     o3c::Float64);
}

o3c::Tensor Extrinsic(const scene::Pose& camera_to_world) {
  const Eigen::Matrix4d w2c = camera_to_world.Inverse().ToMatrix();
  std::vector<double> v(16);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[r * 4 + c] = w2c(r, c);
  return o3c::Tensor(v, {4, 4}, o3c::Float64);
}

o3g::Image DepthImage(const cv::Mat& depth) {
  cv::Mat d = depth.clone();
  cv::patchNaNs(d, 0.0);
  o3c::Tensor t(reinterpret_cast<const float*>(d.data), {d.rows, d.cols, 1}, o3c::Float32);
  return o3g::Image(t.Clone());
}

o3g::Image ColourImage(const cv::Mat& rgb) {
  cv::Mat f;
  rgb.convertTo(f, CV_32FC3, 1.0 / 255.0);
  o3c::Tensor t(reinterpret_cast<const float*>(f.data), {f.rows, f.cols, 3}, o3c::Float32);
  return o3g::Image(t.Clone());
}

struct Keyframe {
  scene::Pose pose;
  scene::CameraInfo camera;
  cv::Mat rgb;    // CV_32FC3 [0, 1]
  cv::Mat depth;  // CV_32FC1 m
};

cv::Vec3f Bilinear(const cv::Mat& img, float x, float y) {
  const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, img.cols - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(y)), 0, img.rows - 1);
  const int x1 = std::min(x0 + 1, img.cols - 1), y1 = std::min(y0 + 1, img.rows - 1);
  const float ax = std::clamp(x - x0, 0.0f, 1.0f), ay = std::clamp(y - y0, 0.0f, 1.0f);
  const cv::Vec3f a = img.at<cv::Vec3f>(y0, x0), b = img.at<cv::Vec3f>(y0, x1),
                  c = img.at<cv::Vec3f>(y1, x0), d = img.at<cv::Vec3f>(y1, x1);
  return (a * (1 - ax) + b * ax) * (1 - ay) + (c * (1 - ax) + d * ax) * ay;
}

class OpenFusedScene : public FusedScene {
 public:
  explicit OpenFusedScene(const FusedSceneOptions& o)
      : options_(o),
        grid_({"tsdf", "weight", "color"}, {o3c::Float32, o3c::Float32, o3c::Float32},
              {{1}, {1}, {3}}, static_cast<float>(o.voxel_size_m), 8, 4000) {
    options_.Validate();
    trunc_mult_ = o.sdf_trunc_m > 0 ? static_cast<float>(o.sdf_trunc_m / o.voxel_size_m) : 4.0f;
  }

  void Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera) override {
    if (frame.depth.empty() || frame.rgb.empty() || frame.depth.size() != frame.rgb.size())
      throw std::invalid_argument("fused scene: frame " + frame.id + " lacks rgb or depth");
    const o3g::Image depth = DepthImage(frame.depth);
    const o3g::Image colour = ColourImage(frame.rgb);
    const o3c::Tensor K = Intrinsic(camera), T = Extrinsic(frame.pose);
    const float dmax = static_cast<float>(options_.depth_max_m);
    const o3c::Tensor blocks = grid_.GetUniqueBlockCoordinates(depth, K, T, 1.0f, dmax, trunc_mult_);
    grid_.Integrate(blocks, depth, colour, K, T, 1.0f, dmax, trunc_mult_);
    ++integrated_;
  }

  void AddKeyframe(const scene::RgbdSample& frame, const scene::CameraInfo& camera) override {
    Keyframe kf;
    kf.pose = frame.pose;
    kf.camera = camera;
    frame.rgb.convertTo(kf.rgb, CV_32FC3, 1.0 / 255.0);
    kf.depth = frame.depth.clone();
    cv::patchNaNs(kf.depth, 0.0);
    keyframes_.push_back(std::move(kf));
    poses_.push_back(frame.pose);
  }

  size_t Keyframes() const override { return keyframes_.size(); }

  fusion::ViewCandidates Render(const scene::Pose& pose, const scene::CameraInfo& camera) override {
    const int w = camera.image_width, h = camera.image_height, k = options_.k;
    fusion::ViewCandidates c;
    c.pose = pose;
    c.camera = camera;
    c.depth = cv::Mat::zeros(h, w, CV_32FC1);
    c.normals = cv::Mat::zeros(h, w, CV_32FC3);
    c.observed = cv::Mat::zeros(h, w, CV_8UC1);
    c.confidence = cv::Mat::zeros(h, w, CV_32FC1);
    c.tsdf_colour = cv::Mat::zeros(h, w, CV_32FC3);
    c.blended = cv::Mat::zeros(h, w, CV_32FC3);
    for (int j = 0; j < k; ++j) {
      c.colours.push_back(cv::Mat::zeros(h, w, CV_32FC3));
      c.weights.push_back(cv::Mat::zeros(h, w, CV_32FC1));
    }
    const Eigen::Matrix3d R = pose.rotation().toRotationMatrix();
    if (integrated_ > 0) {
      // Only the active blocks: the key buffer also holds unused capacity.
      o3c::HashMap map = grid_.GetHashMap();
      const o3c::Tensor active = map.GetActiveIndices().To(o3c::Int64);
      const o3c::Tensor blocks = map.GetKeyTensor().IndexGet({active});
      // Open3D's range map must tile the image exactly (else it reads past it): the largest of
      // 8, 4, 2, 1 dividing both sizes.
      int down = 8;
      while (down > 1 && (w % down != 0 || h % down != 0)) down /= 2;
      const auto result = grid_.RayCast(blocks, Intrinsic(camera), Extrinsic(pose), w, h,
                                        {"depth", "normal", "color"}, 1.0f, 0.05f,
                                        static_cast<float>(options_.depth_max_m), 1.0f, trunc_mult_,
                                        down);
      const o3c::Tensor depth = result.at("depth").Contiguous().To(o3c::Float32);
      const o3c::Tensor normal = result.at("normal").Contiguous().To(o3c::Float32);
      const o3c::Tensor colour = result.at("color").Contiguous().To(o3c::Float32);
      const float* dp = depth.GetDataPtr<float>();
      const float* np = normal.GetDataPtr<float>();
      const float* cp = colour.GetDataPtr<float>();
      for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
          const size_t i = static_cast<size_t>(v) * w + u;
          const float z = dp[i];
          if (!(z > 0) || !std::isfinite(z)) continue;
          c.depth.at<float>(v, u) = z;
          c.observed.at<uint8_t>(v, u) = 255;
          Eigen::Vector3d n_world(np[3 * i], np[3 * i + 1], np[3 * i + 2]);
          Eigen::Vector3d n = R.transpose() * n_world;
          if (n.norm() > 1e-6) n.normalize();
          c.normals.at<cv::Vec3f>(v, u) = cv::Vec3f(n.x(), n.y(), n.z());
          c.tsdf_colour.at<cv::Vec3f>(v, u) =
              cv::Vec3f(std::clamp(cp[3 * i], 0.0f, 1.0f), std::clamp(cp[3 * i + 1], 0.0f, 1.0f),
                        std::clamp(cp[3 * i + 2], 0.0f, 1.0f));
        }
      }
    }
    // Keyframe slots: the k nearest keyframes by pose.
    const std::vector<size_t> nearest =
        keyframes_.empty() ? std::vector<size_t>{}
                           : model::NearestPoseIndices(poses_, pose, static_cast<size_t>(k), 0.01);
    c.keyframe_indices.assign(k, -1);
    c.keyframe_ids.assign(k, "");
    c.keyframe_poses.assign(k, scene::Pose());
    for (size_t j = 0; j < nearest.size(); ++j) {
      c.keyframe_indices[j] = static_cast<int>(nearest[j]);
      c.keyframe_poses[j] = keyframes_[nearest[j]].pose;
    }
    const auto& K = camera.camera_matrix;
    const Eigen::Vector3d centre = pose.translation();
    long observed = 0, blended = 0;
    double angle_sum = 0.0, conf_sum = 0.0;
    std::vector<float> wraw(k);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const float z = c.depth.at<float>(v, u);
        if (!(z > 0)) continue;
        ++observed;
        const Eigen::Vector3d Xc((u - K[2]) / K[0] * z, (v - K[5]) / K[4] * z, z);
        const Eigen::Vector3d X = R * Xc + centre;
        const Eigen::Vector3d ray = (X - centre).normalized();
        float wsum = 0.0f;
        double min_angle = 1e9;
        for (size_t j = 0; j < nearest.size(); ++j) {
          wraw[j] = 0.0f;
          const Keyframe& kf = keyframes_[nearest[j]];
          const Eigen::Matrix3d Rj = kf.pose.rotation().toRotationMatrix();
          const Eigen::Vector3d Xj = Rj.transpose() * (X - kf.pose.translation());
          if (Xj.z() <= 0.05) continue;
          const auto& Kj = kf.camera.camera_matrix;
          const float x = static_cast<float>(Kj[0] * Xj.x() / Xj.z() + Kj[2]);
          const float y = static_cast<float>(Kj[4] * Xj.y() / Xj.z() + Kj[5]);
          if (x < 0 || y < 0 || x > kf.rgb.cols - 1 || y > kf.rgb.rows - 1) continue;
          const float dj = kf.depth.at<float>(static_cast<int>(y + 0.5f), static_cast<int>(x + 0.5f));
          const double tol = 0.05 * Xj.z() + 2.0 * options_.voxel_size_m;
          if (!(dj > 0) || std::abs(dj - Xj.z()) > tol) continue;
          const Eigen::Vector3d rayj = (X - kf.pose.translation()).normalized();
          const double angle = std::acos(std::clamp(ray.dot(rayj), -1.0, 1.0)) * 180.0 / M_PI;
          const double dist_ratio = (X - kf.pose.translation()).norm() / (X - centre).norm();
          const double penalty = angle / kAngleSigmaDeg + 0.5 * std::max(0.0, dist_ratio - 1.0);
          wraw[j] = static_cast<float>(std::exp(-penalty * penalty) + 1e-4);
          wsum += wraw[j];
          min_angle = std::min(min_angle, angle);
          c.colours[j].at<cv::Vec3f>(v, u) = Bilinear(kf.rgb, x, y);
        }
        if (wsum > 0) {
          cv::Vec3f b(0, 0, 0);
          for (size_t j = 0; j < nearest.size(); ++j) {
            const float wn = wraw[j] / wsum;
            c.weights[j].at<float>(v, u) = wn;
            b += c.colours[j].at<cv::Vec3f>(v, u) * wn;
          }
          c.blended.at<cv::Vec3f>(v, u) = b;
          const double conf = std::exp(-(min_angle / kAngleSigmaDeg) * (min_angle / kAngleSigmaDeg));
          c.confidence.at<float>(v, u) = static_cast<float>(conf);
          conf_sum += conf;
          angle_sum += min_angle;
          ++blended;
        } else {
          c.blended.at<cv::Vec3f>(v, u) = c.tsdf_colour.at<cv::Vec3f>(v, u);
        }
      }
    }
    const double total = static_cast<double>(w) * h;
    c.coverage.observed_fraction = observed / total;
    c.coverage.blended_fraction = blended / total;
    c.coverage.mean_angle_deg = blended > 0 ? angle_sum / blended : 0.0;
    c.coverage.score = conf_sum / total;
    return c;
  }

  void SaveTsdf(const std::string& path) const override { grid_.Save(path); }
  const FusedSceneOptions& options() const override { return options_; }

 private:
  FusedSceneOptions options_;
  o3g::VoxelBlockGrid grid_;
  float trunc_mult_ = 4.0f;
  size_t integrated_ = 0;
  std::vector<Keyframe> keyframes_;
  std::vector<scene::Pose> poses_;
};

}  // namespace

std::unique_ptr<FusedScene> MakeFusedScene(const FusedSceneOptions& options) {
  options.Validate();
  return std::make_unique<OpenFusedScene>(options);
}

}  // namespace p2i::refine
