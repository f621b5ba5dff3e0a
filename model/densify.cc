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

std::string DensifySummary(const DensifyReport& report, const P2iConfig& config) {
  if (report.added == 0 && report.skipped == 0) return "";
  char line[256];
  std::snprintf(line, sizeof(line), "densified: %d views of %s near the training poses (%.1f s)",
                report.added, config.densify_method.c_str(), report.render_s);
  std::string out = line;
  if (config.densify_min_gap_m > 0) {
    std::snprintf(line, sizeof(line),
                  "; %d candidates skipped within %.3g m and %.3g deg of a training frame",
                  report.skipped, config.densify_min_gap_m, config.densify_min_gap_deg);
    out += line;
  }
  return out;
}

bool NearAnyFrame(const scene::Pose& pose, const std::vector<scene::RgbdSample>& frames,
                  double gap_m, double gap_deg) {
  for (const scene::RgbdSample& f : frames)
    if (scene::Pose::TranslationDistance(f.pose, pose) <= gap_m &&
        scene::Pose::RotationDistanceDeg(f.pose, pose) <= gap_deg)
      return true;
  return false;
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
  const bool gap = config.densify_min_gap_m > 0;
  int added = 0, skipped = 0;
  for (int candidate = 0; candidate < n; ++candidate) {
    const scene::RgbdSample& base = train.frames[pick(rng)];
    const scene::Pose pose = NearbyPose(base.pose, config.densify_offset_m, config.densify_angle_deg, rng);
    if (gap && NearAnyFrame(pose, train.frames, config.densify_min_gap_m, config.densify_min_gap_deg)) {
      ++skipped;
      continue;
    }
    const int i = added++;
    scene::RgbdSample view = renderer->Render(pose);
    view.pose = pose;
    view.stamp = base.stamp;
    char id[32];
    std::snprintf(id, sizeof(id), "%s%06d", kDensifiedIdPrefix, i);
    view.id = id;
    out.frames.push_back(std::move(view));
  }
  if (report != nullptr) {
    report->added = added;
    report->skipped = skipped;
    report->render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return out;
}

}  // namespace p2i::model
