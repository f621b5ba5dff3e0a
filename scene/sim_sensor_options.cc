/// @file sim_sensor_options.cc
/// @brief Sensor effect options: presets, YAML parsing, validation.
#include "scene/sim_sensor_options.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>

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

SimSensorOptions SimSensorOptions::Realistic(std::uint32_t seed) {
  SimSensorOptions o = Kinect(seed);
  o.auto_exposure = 0.6;
  o.exposure_drift = 0.08;
  o.white_balance_drift = 0.04;
  o.exposure_time_s = 0.03;
  o.motion_blur_samples = 5;
  return o;
}

bool SimSensorOptions::IsPreset(const std::string& preset) {
  return preset == "none" || preset == "kinect" || preset == "realistic";
}

SimSensorOptions SimSensorOptions::FromPreset(const std::string& preset, std::uint32_t seed) {
  if (preset == "kinect") return Kinect(seed);
  if (preset == "realistic") return Realistic(seed);
  if (preset != "none")
    throw std::invalid_argument("sensor preset '" + preset +
                                "' is unknown (use none, kinect or realistic)");
  SimSensorOptions o;
  o.seed = seed;
  return o;
}

namespace {

struct Field {
  const char* key;
  double SimSensorOptions::*member;
};

constexpr Field kFields[] = {
    {"depth_noise_sigma", &SimSensorOptions::depth_noise_sigma},
    {"depth_noise_quadratic", &SimSensorOptions::depth_noise_quadratic},
    {"min_range", &SimSensorOptions::min_range},
    {"max_range", &SimSensorOptions::max_range},
    {"grazing_angle_deg", &SimSensorOptions::grazing_angle_deg},
    {"depth_dropout", &SimSensorOptions::depth_dropout},
    {"rgb_noise_sigma", &SimSensorOptions::rgb_noise_sigma},
    {"auto_exposure", &SimSensorOptions::auto_exposure},
    {"exposure_target", &SimSensorOptions::exposure_target},
    {"exposure_drift", &SimSensorOptions::exposure_drift},
    {"white_balance_drift", &SimSensorOptions::white_balance_drift},
    {"drift_period_s", &SimSensorOptions::drift_period_s},
    {"exposure_time_s", &SimSensorOptions::exposure_time_s},
};

std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

SimSensorOptions SimSensorOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const auto fail = [&](const YAML::Node& n, const std::string& what) {
    const int line = n.Mark().is_null() ? 0 : n.Mark().line + 1;
    throw std::runtime_error(source + ":" + std::to_string(line) + ": sensor options: " + what);
  };
  SimSensorOptions o;
  if (!node.IsDefined() || node.IsNull()) return o;
  if (!node.IsMap()) fail(node, "must be a map");
  std::set<std::string> keys = {"preset", "seed", "motion_blur_samples", "pixel_samples"};
  for (const Field& f : kFields) keys.insert(f.key);
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (keys.count(key) == 0) {
      std::string list;
      for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
      fail(kv.first, "unknown key '" + key + "' (allowed: " + list + ")");
    }
  }
  if (node["preset"]) {
    const std::string preset = node["preset"].as<std::string>();
    if (!IsPreset(preset))
      fail(node["preset"], "unknown preset '" + preset + "' (use none, kinect or realistic)");
    o = FromPreset(preset);
  }
  for (const Field& f : kFields) {
    if (!node[f.key]) continue;
    try {
      o.*f.member = node[f.key].as<double>();
    } catch (const YAML::Exception&) {
      fail(node[f.key], std::string(f.key) + " must be a number");
    }
  }
  const auto get_int = [&](const char* key, auto* out) {
    if (!node[key]) return;
    try {
      *out = node[key].as<std::remove_pointer_t<decltype(out)>>();
    } catch (const YAML::Exception&) {
      fail(node[key], std::string(key) + " must be a non-negative integer");
    }
  };
  get_int("seed", &o.seed);
  get_int("motion_blur_samples", &o.motion_blur_samples);
  get_int("pixel_samples", &o.pixel_samples);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    fail(node, e.what());
  }
  return o;
}

void SimSensorOptions::Validate() const {
  for (const Field& f : kFields) {
    const double v = this->*f.member;
    if (!std::isfinite(v) || v < 0.0) {
      throw std::invalid_argument(std::string(f.key) + " must be finite and >= 0 (got " + Num(v) +
                                  ")");
    }
  }
  const auto at_most = [](const char* key, double v, double max, const char* why) {
    if (v > max) {
      throw std::invalid_argument(std::string(key) + " must be at most " + Num(max) + " (got " +
                                  Num(v) + ")" + why);
    }
  };
  if (grazing_angle_deg >= 90.0) {
    throw std::invalid_argument("grazing_angle_deg must be below 90 (got " +
                                Num(grazing_angle_deg) + "; 0 turns it off)");
  }
  at_most("depth_dropout", depth_dropout, 1.0, ": a probability");
  at_most("auto_exposure", auto_exposure, 1.0, ": a strength in [0, 1]");
  at_most("exposure_drift", exposure_drift, 0.5, "");
  at_most("white_balance_drift", white_balance_drift, 0.5, "");
  at_most("exposure_time_s", exposure_time_s, 1.0, "");
  if (!(exposure_target > 0.0) || exposure_target > 1.0) {
    throw std::invalid_argument("exposure_target must be in (0, 1] (got " + Num(exposure_target) +
                                ")");
  }
  if (!(drift_period_s > 0.0)) {
    throw std::invalid_argument("drift_period_s must be > 0 (got " + Num(drift_period_s) + ")");
  }
  if (motion_blur_samples < 1 || motion_blur_samples > 64) {
    throw std::invalid_argument("motion_blur_samples must be in [1, 64] (got " +
                                std::to_string(motion_blur_samples) + ")");
  }
  if (pixel_samples < 1 || pixel_samples > 7 || pixel_samples % 2 == 0) {
    throw std::invalid_argument("pixel_samples must be odd, 1 to 7 (got " +
                                std::to_string(pixel_samples) + "): the centre ray gives depth");
  }
  if (max_range > 0.0 && min_range >= max_range) {
    throw std::invalid_argument("min_range (" + Num(min_range) + ") must be below max_range (" +
                                Num(max_range) + ")");
  }
}

bool SimSensorOptions::AnyNoise() const {
  return rgb_noise_sigma > 0 || depth_noise_sigma > 0 || depth_noise_quadratic > 0 ||
         min_range > 0 || max_range > 0 || grazing_angle_deg > 0 || depth_dropout > 0;
}

bool SimSensorOptions::AnyColour() const {
  return auto_exposure > 0 || exposure_drift > 0 || white_balance_drift > 0;
}

}  // namespace p2i::scene
