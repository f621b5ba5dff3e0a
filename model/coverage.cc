/// @file coverage.cc
/// @brief Combined pose distance, nearest poses and the coverage score.
#include "model/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "scene/strict_yaml_reader.h"

namespace p2i::model {
namespace {

void CheckPositive(double v, const char* name) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw std::invalid_argument(std::string("CoverageOptions.") + name +
                                " must be positive and finite, got " + std::to_string(v));
  }
}

}  // namespace

double CombinedPoseDistance(const scene::Pose& a, const scene::Pose& b,
                            double metres_per_degree) {
  return scene::Pose::TranslationDistance(a, b) +
         metres_per_degree * scene::Pose::RotationDistanceDeg(a, b);
}

std::vector<size_t> NearestPoseIndices(const std::vector<scene::Pose>& poses,
                                       const scene::Pose& query, size_t k,
                                       double metres_per_degree) {
  std::vector<std::pair<double, size_t>> d;
  d.reserve(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    d.emplace_back(CombinedPoseDistance(query, poses[i], metres_per_degree), i);
  }
  const size_t m = std::min(k, d.size());
  std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(m), d.end());
  std::vector<size_t> out;
  out.reserve(m);
  for (size_t i = 0; i < m; ++i) out.push_back(d[i].second);
  return out;
}

CoverageOptions CoverageOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"metres_per_degree", "falloff", "fallback_spacing_m"}, "coverage options");
  CoverageOptions o;
  if (node["metres_per_degree"]) o.metres_per_degree = r.Double(node["metres_per_degree"], "metres_per_degree");
  if (node["falloff"]) o.falloff = r.Double(node["falloff"], "falloff");
  if (node["fallback_spacing_m"]) o.fallback_spacing_m = r.Double(node["fallback_spacing_m"], "fallback_spacing_m");
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void CoverageOptions::Validate() const {
  if (!std::isfinite(metres_per_degree) || metres_per_degree < 0.0) {
    throw std::invalid_argument(
        "CoverageOptions.metres_per_degree must be finite and >= 0, got " +
        std::to_string(metres_per_degree));
  }
  CheckPositive(falloff, "falloff");
  CheckPositive(fallback_spacing_m, "fallback_spacing_m");
}

CoverageScorer::CoverageScorer(std::vector<scene::Pose> training_poses, CoverageOptions options)
    : poses_(std::move(training_poses)), options_(options) {
  options_.Validate();
  if (poses_.empty()) {
    throw std::invalid_argument("CoverageScorer: no training poses (the training split is empty)");
  }
  std::vector<double> nearest;
  for (size_t i = 0; i < poses_.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < poses_.size(); ++j) {
      if (j == i) continue;
      best = std::min(best, CombinedPoseDistance(poses_[i], poses_[j],
                                                 options_.metres_per_degree));
    }
    if (std::isfinite(best)) nearest.push_back(best);
  }
  spacing_ = options_.fallback_spacing_m;
  if (!nearest.empty()) {
    const auto mid = nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2);
    std::nth_element(nearest.begin(), mid, nearest.end());
    if (*mid > 0.0) spacing_ = *mid;
  }
}

double CoverageScorer::NearestDistance(const scene::Pose& pose) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : poses_) {
    best = std::min(best, CombinedPoseDistance(pose, p, options_.metres_per_degree));
  }
  return best;
}

double CoverageScorer::Score(const scene::Pose& pose) const {
  const double x = NearestDistance(pose) / (options_.falloff * spacing_);
  return std::exp(-x * x);
}

}  // namespace p2i::model
