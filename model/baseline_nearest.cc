/// @file baseline_nearest.cc
/// @brief Nearest-keyframe baseline.
#include "model/baseline_nearest.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

#include "model/coverage.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::model {

NearestKeyframeOptions NearestKeyframeOptions::FromYaml(const YAML::Node& node,
                                                        const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node, {"metres_per_degree"}, "nearest_keyframe options");
  NearestKeyframeOptions o;
  if (node["metres_per_degree"]) o.metres_per_degree = r.Double(node["metres_per_degree"], "metres_per_degree");
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  return o;
}

void NearestKeyframeOptions::Validate() const {
  if (!std::isfinite(metres_per_degree) || metres_per_degree < 0.0) {
    throw std::invalid_argument(
        "NearestKeyframeOptions.metres_per_degree must be finite and >= 0, got " +
        std::to_string(metres_per_degree));
  }
}

NearestKeyframe::NearestKeyframe(scene::RgbdDataset training, NearestKeyframeOptions options)
    : training_(std::move(training)), options_(options) {
  options_.Validate();
  if (training_.frames.empty()) {
    throw std::invalid_argument("NearestKeyframe: the training dataset has no frames");
  }
  poses_.reserve(training_.frames.size());
  for (const auto& f : training_.frames) poses_.push_back(f.pose);
}

size_t NearestKeyframe::NearestIndex(const scene::Pose& pose) const {
  return NearestPoseIndices(poses_, pose, 1, options_.metres_per_degree).front();
}

scene::RgbdSample NearestKeyframe::Render(const scene::Pose& pose) {
  const scene::RgbdSample& f = training_.frames[NearestIndex(pose)];
  scene::RgbdSample v;
  v.stamp = f.stamp;
  v.pose = pose;
  v.rgb = f.rgb.clone();
  v.depth = f.depth.clone();
  v.id = "nearest:" + f.id;
  return v;
}

}  // namespace p2i::model
