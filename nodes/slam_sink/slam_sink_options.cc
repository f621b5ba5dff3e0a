/// @file slam_sink_options.cc
/// @brief SlamSinkOptions YAML parsing and validation.
#include "nodes/slam_sink/slam_sink_options.h"

#include <functional>
#include <map>
#include <stdexcept>

#include "nodes/runtime/option_error.h"

namespace p2i::slam_sink {

SlamSinkOptions SlamSinkOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  SlamSinkOptions o;
  if (!node || node.IsNull()) return o;
  if (!node.IsMap()) {
    throw std::runtime_error("SlamSinkOptions: " + source + " must be a YAML mapping");
  }
  using Setter = std::function<void(const YAML::Node&)>;
  const std::map<std::string, Setter> setters = {
      {"out_dir", [&](const YAML::Node& v) { o.writer.out_dir = v.as<std::string>(); }},
      {"append", [&](const YAML::Node& v) { o.writer.append = v.as<bool>(); }},
      {"fsync", [&](const YAML::Node& v) { o.writer.fsync = v.as<bool>(); }},
      {"write_associations",
       [&](const YAML::Node& v) { o.writer.write_associations = v.as<bool>(); }},
      {"png_compression", [&](const YAML::Node& v) { o.writer.png_compression = v.as<int>(); }},
      {"depth_scale", [&](const YAML::Node& v) { o.writer.depth_scale = v.as<double>(); }},
      {"check", [&](const YAML::Node& v) { o.check = v.as<bool>(); }},
      {"policy", [&](const YAML::Node& v) { o.policy = v.as<std::string>(); }},
      {"write_real", [&](const YAML::Node& v) { o.write_real = v.as<bool>(); }},
      {"odometry_method", [&](const YAML::Node& v) { o.checker.method = v.as<std::string>(); }},
      {"max_translation_error_m",
       [&](const YAML::Node& v) { o.checker.max_translation_error_m = v.as<double>(); }},
      {"max_rotation_error_deg",
       [&](const YAML::Node& v) { o.checker.max_rotation_error_deg = v.as<double>(); }},
      {"min_coverage", [&](const YAML::Node& v) { o.checker.min_coverage = v.as<double>(); }},
      {"min_valid_depth_fraction",
       [&](const YAML::Node& v) { o.checker.min_valid_depth_fraction = v.as<double>(); }},
      {"min_depth_m", [&](const YAML::Node& v) { o.checker.min_depth_m = v.as<double>(); }},
      {"max_depth_m", [&](const YAML::Node& v) { o.checker.max_depth_m = v.as<double>(); }},
      {"max_baseline_m", [&](const YAML::Node& v) { o.checker.max_baseline_m = v.as<double>(); }},
      {"max_baseline_deg",
       [&](const YAML::Node& v) { o.checker.max_baseline_deg = v.as<double>(); }},
  };
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const auto it = setters.find(key);
    if (it == setters.end()) {
      throw std::runtime_error("SlamSinkOptions: unknown key '" + key + "' in " + source +
                               " (see docs/SLAM_SINK.md for the keys)");
    }
    try {
      it->second(kv.second);
    } catch (const YAML::Exception& e) {
      throw std::runtime_error("SlamSinkOptions: bad value for '" + key + "' in " + source +
                               ": " + e.what());
    }
  }
  o.Validate();
  return o;
}

void SlamSinkOptions::Validate() const {
  writer.Validate();
  checker.Validate();
  runtime::CheckOption(policy == "flag" || policy == "drop", "slam_sink", "policy", policy,
                       "be flag or drop",
                       "policy:=flag writes failing frames, marked; policy:=drop does not write them");
}

}  // namespace p2i::slam_sink
