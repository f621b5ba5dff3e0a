/// @file sim_sensor_options.cc
/// @brief Sensor effect options: Kinect preset, YAML parsing, validation.
#include "scene/sim_sensor_options.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <stdexcept>

namespace p2i::scene {

SimSensorOptions SimSensorOptions::Kinect(std::uint32_t seed) {
  SimSensorOptions o;
  o.rgb_noise_sigma = 2.0;
  o.depth_noise_sigma = 0.0012;
  o.depth_noise_quadratic = 0.0019;
  o.min_range = 0.5;
  o.max_range = 4.5;
  o.grazing_angle_deg = 75.0;
  o.depth_dropout = 0.005;
  o.seed = seed;
  return o;
}

SimSensorOptions SimSensorOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const auto fail = [&](const YAML::Node& n, const std::string& what) {
    const int line = n.Mark().is_null() ? 0 : n.Mark().line + 1;
    throw std::runtime_error(source + ":" + std::to_string(line) + ": sensor options: " + what);
  };
  SimSensorOptions o;
  if (!node.IsDefined() || node.IsNull()) return o;
  if (!node.IsMap()) fail(node, "must be a map");
  static const std::set<std::string> kKeys = {
      "preset",    "rgb_noise_sigma", "depth_noise_sigma", "depth_noise_quadratic",
      "min_range", "max_range",       "grazing_angle_deg", "depth_dropout",
      "seed"};
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (kKeys.count(key) == 0) fail(kv.first, "unknown key '" + key + "'");
  }
  if (node["preset"]) {
    const std::string preset = node["preset"].as<std::string>();
    if (preset == "kinect") {
      o = Kinect();
    } else if (preset != "none") {
      fail(node["preset"], "unknown preset '" + preset + "' (use none or kinect)");
    }
  }
  const auto get = [&](const char* key, double* out) {
    if (!node[key]) return;
    try {
      *out = node[key].as<double>();
    } catch (const YAML::Exception&) {
      fail(node[key], std::string(key) + " must be a number");
    }
  };
  get("rgb_noise_sigma", &o.rgb_noise_sigma);
  get("depth_noise_sigma", &o.depth_noise_sigma);
  get("depth_noise_quadratic", &o.depth_noise_quadratic);
  get("min_range", &o.min_range);
  get("max_range", &o.max_range);
  get("grazing_angle_deg", &o.grazing_angle_deg);
  get("depth_dropout", &o.depth_dropout);
  if (node["seed"]) {
    try {
      o.seed = node["seed"].as<std::uint32_t>();
    } catch (const YAML::Exception&) {
      fail(node["seed"], "seed must be a non-negative integer");
    }
  }
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    fail(node, e.what());
  }
  return o;
}

void SimSensorOptions::Validate() const {
  for (double v : {rgb_noise_sigma, depth_noise_sigma, depth_noise_quadratic, min_range, max_range,
                   grazing_angle_deg, depth_dropout}) {
    if (!std::isfinite(v) || v < 0.0) {
      throw std::invalid_argument("sensor options must be finite and >= 0");
    }
  }
  if (grazing_angle_deg >= 90.0) {
    throw std::invalid_argument("grazing_angle_deg must be below 90 (0 turns it off)");
  }
  if (depth_dropout > 1.0) throw std::invalid_argument("depth_dropout is a probability in [0, 1]");
  if (max_range > 0.0 && min_range >= max_range) {
    throw std::invalid_argument("min_range must be below max_range");
  }
}

bool SimSensorOptions::AnyEnabled() const {
  return rgb_noise_sigma > 0 || depth_noise_sigma > 0 || depth_noise_quadratic > 0 ||
         min_range > 0 || max_range > 0 || grazing_angle_deg > 0 || depth_dropout > 0;
}

}  // namespace p2i::scene
