/// @file yaml_flow.h
/// @brief A YAML value as one line of flow text ({k: 2}, [1, 2], a scalar as written): how
/// parameters, launch files and `p2i param` show and pass values.
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

namespace p2i::util {

inline std::string YamlFlow(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

}  // namespace p2i::util
