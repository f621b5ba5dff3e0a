/// @file strict_yaml_reader.h
/// @brief The project's strict YAML reader (scene and trajectory options, method options, bench
/// configs): unknown keys and bad values become exceptions naming the source, line and key.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace p2i::scene {

/// Reads values from YAML nodes; every problem throws std::runtime_error "SOURCE:LINE: what".
/// Stateless apart from the source name: thread-compatible.
class StrictYamlReader {
 public:
  explicit StrictYamlReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& what) const {
    std::ostringstream os;
    os << source_;
    if (node.IsDefined() && !node.Mark().is_null()) os << ":" << node.Mark().line + 1;
    os << ": " << what;
    throw std::runtime_error(os.str());
  }

  void CheckMap(const YAML::Node& node, const std::string& what) const {
    if (!node.IsMap()) Fail(node, what + " must be a map");
  }

  /// Unknown keys are errors: a typo must not silently fall back to a default.
  void CheckKeys(const YAML::Node& node, const std::set<std::string>& allowed,
                 const std::string& what) const {
    CheckMap(node, what);
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      if (allowed.count(key) == 0) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        Fail(kv.first, "unknown key '" + key + "' in " + what + " (allowed: " + list + ")");
      }
    }
  }

  YAML::Node Require(const YAML::Node& node, const std::string& key,
                     const std::string& what) const {
    const YAML::Node child = node[key];
    if (!child.IsDefined() || child.IsNull()) Fail(node, "missing key '" + key + "' in " + what);
    return child;
  }

  double Double(const YAML::Node& node, const std::string& what) const {
    try {
      const double v = node.as<double>();
      if (!std::isfinite(v)) Fail(node, what + " must be finite");
      return v;
    } catch (const YAML::Exception&) {
      Fail(node, what + " must be a number");
    }
  }

  /// A whole number (as Double, then "WHAT must be an integer").
  int Int(const YAML::Node& node, const std::string& what) const {
    const double v = Double(node, what);
    if (v != std::floor(v)) Fail(node, what + " must be an integer");
    return static_cast<int>(v);
  }

  std::string String(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) Fail(node, what + " must be a string");
    return node.as<std::string>();
  }

  Eigen::Vector3d Vec3(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() != 3) Fail(node, what + " must be a list of 3 numbers");
    return {Double(node[0], what), Double(node[1], what), Double(node[2], what)};
  }

  void OptionalDouble(const YAML::Node& map, const std::string& key, const std::string& what,
                      double* out) const {
    const YAML::Node n = map[key];
    if (n.IsDefined() && !n.IsNull()) *out = Double(n, what + "." + key);
  }
  void OptionalVec3(const YAML::Node& map, const std::string& key, const std::string& what,
                    Eigen::Vector3d* out) const {
    const YAML::Node n = map[key];
    if (n.IsDefined() && !n.IsNull()) *out = Vec3(n, what + "." + key);
  }

 private:
  std::string source_;
};

}  // namespace p2i::scene
