/// @file parameters.cc
/// @brief Parameter loading, precedence and the undeclared-parameter check.
#include "nodes/runtime/parameters.h"

#include <fstream>
#include <sstream>

namespace p2i::runtime {

Parameters::Parameters(const NodeArgs& args) {
  for (const auto& f : args.params_files) LoadFile(f);
  for (const auto& [k, v] : args.overrides) SetOverride(k, v);
}

void Parameters::LoadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw StartupError("--params-file '" + path + "': cannot open (check the path)");
  }
  YAML::Node root;
  try {
    root = YAML::Load(in);
  } catch (const YAML::Exception& e) {
    throw StartupError("--params-file '" + path + "': invalid YAML: " + e.what());
  }
  if (root.IsNull()) return;  // an empty file sets nothing
  if (!root.IsMap()) {
    throw StartupError("--params-file '" + path +
                       "': must be a YAML mapping {parameter: value, ...}");
  }
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    supplied_[key] = Supplied{YAML::Clone(kv.second), path};
  }
}

void Parameters::SetOverride(const std::string& key, const std::string& yaml_value,
                             const std::string& source) {
  YAML::Node value;
  try {
    value = yaml_value.empty() ? YAML::Node(std::string()) : YAML::Load(yaml_value);
  } catch (const YAML::Exception& e) {
    throw StartupError(source + ": value of '" + key + ":=" + yaml_value +
                       "' is not a YAML scalar/flow value: " + e.what());
  }
  supplied_[key] = Supplied{value, source};
}

std::string Parameters::ToFlow(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

void Parameters::Record(const std::string& name, const std::string& description,
                        const YAML::Node& default_node, const YAML::Node& value_node,
                        const std::string& source) {
  if (declared_.count(name)) return;
  declared_[name] = Info{name, description, ToFlow(default_node), ToFlow(value_node), source};
}

void Parameters::ThrowConversion(const std::string& name, const Supplied& s,
                                 const std::string& default_text, const std::string& what) const {
  throw StartupError("parameter '" + name + "' from " + s.source + ": value '" +
                     ToFlow(s.value) + "' does not have the declared type (default is '" +
                     default_text + "'): " + what);
}

void Parameters::CheckAllDeclared() const {
  std::ostringstream msg;
  int unknown = 0;
  for (const auto& [key, s] : supplied_) {
    if (declared_.count(key)) continue;
    msg << (unknown ? "; " : "") << "unknown parameter '" << key << "' (from " << s.source
        << ")";
    ++unknown;
  }
  if (unknown == 0) return;
  msg << ". Declared parameters:";
  for (const auto& [name, info] : declared_) msg << " " << name;
  throw StartupError(msg.str());
}

std::string Parameters::Describe() const {
  std::ostringstream out;
  for (const auto& [name, info] : declared_) {
    out << "  " << name << " = " << info.value_text << "  (" << info.source
        << "; default " << info.default_text << ")  " << info.description << "\n";
  }
  return out.str();
}

}  // namespace p2i::runtime
