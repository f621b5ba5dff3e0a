/// @file parameters.cc
/// @brief Parameter loading, precedence and the undeclared-parameter check.
#include "nodes/runtime/parameters.h"

#include <fstream>
#include <sstream>

#include "util/yaml_flow.h"

namespace p2i::runtime {

Parameters::Parameters(const NodeArgs& args, const std::string& node_name,
                       const std::string& full_name)
    : node_name_(node_name), full_name_(full_name) {
  for (const auto& f : args.params_files) LoadFile(f);
  for (const auto& [k, v] : args.overrides) SetOverride(k, v);
}

Parameters::Parameters(const NodeArgs& args) {
  for (const auto& f : args.params_files) LoadFile(f);
  for (const auto& [k, v] : args.overrides) SetOverride(k, v);
}

void Parameters::LoadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    throw StartupError("--params-file '" + path + "': cannot open (check the path)");
  }
  std::stringstream text_stream;
  text_stream << in.rdbuf();
  const std::string text = text_stream.str();
  // `p2i launch` writes inline parameters as "name: value  #@ LAUNCH_FILE:LINE": errors then
  // name that line instead of the temporary file.
  std::map<std::string, std::string> launch_sources;
  {
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
      const auto colon = line.find(':');
      const auto mark = line.rfind("  #@ ");
      if (colon == std::string::npos || mark == std::string::npos || mark < colon) continue;
      launch_sources[line.substr(0, colon)] = line.substr(mark + 5) + " (launch file)";
    }
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw StartupError("--params-file '" + path + "': invalid YAML: " + e.what());
  }
  if (root.IsNull()) return;  // an empty file sets nothing
  if (!root.IsMap()) {
    throw StartupError("--params-file '" + path +
                       "': must be a YAML mapping {parameter: value, ...}");
  }
  // ROS 2 format: every top-level value is a map with a `ros__parameters` key.
  bool ros = root.size() > 0;
  for (const auto& kv : root) ros = ros && kv.second.IsMap() && kv.second["ros__parameters"];
  if (ros) {
    YAML::Node merged(YAML::NodeType::Map);
    const auto apply = [&](const YAML::Node& section, const std::string& where) {
      const YAML::Node p = section["ros__parameters"];
      if (p.IsNull()) return;
      if (!p.IsMap()) {
        throw StartupError("--params-file '" + path + "': " + where +
                           ": ros__parameters must be a mapping {parameter: value, ...}");
      }
      for (const auto& e : p) merged[e.first.as<std::string>()] = YAML::Clone(e.second);
    };
    for (const auto& kv : root) {
      if (kv.first.as<std::string>() == "/**") apply(kv.second, "/**");
    }
    std::string bare_full = full_name_;
    if (!bare_full.empty() && bare_full[0] == '/') bare_full.erase(0, 1);
    for (const auto& kv : root) {
      const std::string k = kv.first.as<std::string>();
      if (k != "/**" && (k == node_name_ || k == full_name_ || k == bare_full)) apply(kv.second, k);
    }
    root = merged;
  }
  std::map<std::string, int> lines;
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const int line = kv.first.Mark().line + 1;
    if (!lines.emplace(key, line).second) {
      throw StartupError("--params-file '" + path + "':" + std::to_string(line) +
                         ": duplicate parameter '" + key + "' (first at line " +
                         std::to_string(lines[key]) + "); remove one of them");
    }
    auto src = launch_sources.find(key);
    supplied_[key] = Supplied{YAML::Clone(kv.second), src == launch_sources.end() ? path : src->second};
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

std::string Parameters::ToFlow(const YAML::Node& node) { return util::YamlFlow(node); }

void Parameters::Record(const std::string& name, const std::string& description,
                        const YAML::Node& default_node, const YAML::Node& value_node,
                        const std::string& source, const std::string& type) {
  if (declared_.count(name)) return;
  declared_[name] = Info{name, description, ToFlow(default_node), ToFlow(value_node), source, type};
  order_.push_back(name);
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

std::string Parameters::Help() const {
  std::ostringstream out;
  for (const auto& name : order_) {
    const Info& info = declared_.at(name);
    out << "  " << name << " (" << info.type << ", default "
        << (info.default_text.empty() ? "''" : info.default_text) << ")\n      "
        << info.description << "\n";
  }
  return out.str();
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
