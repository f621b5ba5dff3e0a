/// @file densify.cc
/// @brief Geometry-densified training frames (densify.h).

#include "model/densify.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "model/method_registry.h"

namespace p2i::model {

namespace {

// A direction uniform on the unit sphere.
Eigen::Vector3d RandomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    const Eigen::Vector3d v(n(rng), n(rng), n(rng));
    if (v.norm() > 1e-9) return v.normalized();
  }
}

}  // namespace

scene::Pose NearbyPose(const scene::Pose& pose, double max_offset_m, double max_angle_deg,
                       std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d dt = RandomDirection(rng) * (max_offset_m * u(rng));
  const Eigen::Vector3d axis = RandomDirection(rng);
  const double angle = max_angle_deg * u(rng) * M_PI / 180.0;
  return scene::Pose(pose.translation() + dt,
                     pose.rotation() * Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)));
}

scene::RgbdDataset DensifyTrainingFrames(const scene::RgbdDataset& train, const P2iConfig& config,
                                         DensifyReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  scene::RgbdDataset out = train;
  const int n = static_cast<int>(std::lround(config.densify_ratio * static_cast<double>(train.frames.size())));
  if (report != nullptr) *report = DensifyReport{};
  if (n <= 0) return out;
  const MethodInfo* found = FindMethod(config.densify_method);
  if (found == nullptr)
    throw std::invalid_argument("densify_method: method '" + config.densify_method +
                                "' is not one of " + MethodNames());
  const MethodInfo& info = *found;
  if (info.learned)
    throw std::invalid_argument("densify_method '" + info.name +
                                "' is learned: densify with a method built from the frames "
                                "(e.g. fusion or warp)");
  MethodInputs inputs;
  inputs.training = std::make_shared<const scene::RgbdDataset>(train);
  const std::unique_ptr<ViewSynthesizer> renderer =
      info.configure(YAML::Node(), "densify_method " + info.name)(inputs);
  const scene::CameraInfo cam = renderer->Camera();
  if (cam.image_width != train.camera.image_width || cam.image_height != train.camera.image_height)
    throw std::invalid_argument("densify_method '" + info.name + "' renders " +
                                std::to_string(cam.image_width) + "x" + std::to_string(cam.image_height) +
                                ", the training frames are " + std::to_string(train.camera.image_width) +
                                "x" + std::to_string(train.camera.image_height));
  std::mt19937_64 rng(config.seed * 0x9E3779B97F4A7C15ULL + 0xD3A5F1);
  std::uniform_int_distribution<size_t> pick(0, train.frames.size() - 1);
  out.frames.reserve(train.frames.size() + static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const scene::RgbdSample& base = train.frames[pick(rng)];
    const scene::Pose pose = NearbyPose(base.pose, config.densify_offset_m, config.densify_angle_deg, rng);
    scene::RgbdSample view = renderer->Render(pose);
    view.pose = pose;
    view.stamp = base.stamp;
    char id[32];
    std::snprintf(id, sizeof(id), "densify/%06d", i);
    view.id = id;
    out.frames.push_back(std::move(view));
  }
  if (report != nullptr) {
    report->added = n;
    report->render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return out;
}

}  // namespace p2i::model
