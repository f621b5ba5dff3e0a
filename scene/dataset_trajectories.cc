/// @file dataset_trajectories.cc
/// @brief Trajectory spec strings -> generated or loaded trajectories.
#include "scene/dataset_trajectories.h"

#include <filesystem>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "scene/trajectory_io.h"

namespace p2i::scene {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::vector<std::vector<StampedPose>> ResolveTrajectorySpec(const std::string& spec,
                                                            const SimScene* scene) {
  if (spec.empty()) throw std::runtime_error("empty trajectory spec");
  YAML::Node node;
  std::string source = spec;
  if (spec == "arm_sweep" || spec == "adjacent_sweeps" || spec == "orbit" ||
      spec == "random_walk") {
    node["type"] = spec;
    source = "generator '" + spec + "'";
  } else if (spec.front() == '{') {
    try {
      node = YAML::Load(spec);
    } catch (const std::exception& e) {
      throw std::runtime_error("trajectory spec '" + spec + "' is not a valid YAML map: " +
                               e.what());
    }
    source = "inline trajectory spec";
  } else if (EndsWith(spec, ".yaml") || EndsWith(spec, ".yml")) {
    try {
      node = YAML::LoadFile(spec);
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot read trajectory generator file '" + spec + "': " +
                               e.what());
    }
  } else {
    if (!std::filesystem::exists(spec)) {
      throw std::runtime_error(
          "trajectory '" + spec + "' is neither a generator name (arm_sweep, adjacent_sweeps, "
          "orbit, random_walk), an inline map '{type: ...}', a .yaml generator file, nor an "
          "existing TUM trajectory file");
    }
    return {ReadTumTrajectory(spec)};
  }
  if (!node.IsMap()) {
    throw std::runtime_error("trajectory spec '" + spec + "' must be a map with a 'type' key");
  }
  auto out = GenerateTrajectoriesFromYaml(node, source, scene);
  for (const auto& t : out) {
    if (t.empty()) throw std::runtime_error("trajectory spec '" + spec + "' generated no poses");
  }
  return out;
}

void Restamp(std::vector<StampedPose>* trajectory, double rate_hz, double start) {
  if (!(rate_hz > 0.0)) throw std::invalid_argument("Restamp: rate must be positive");
  for (size_t i = 0; i < trajectory->size(); ++i) {
    (*trajectory)[i].stamp = start + static_cast<double>(i) / rate_hz;
  }
}

}  // namespace p2i::scene
