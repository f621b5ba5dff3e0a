/// @file parameters.h
/// @brief Node parameters: declared by the node with a default and a description, valued from
/// --params-file YAML files and KEY:=VALUE overrides; anything not declared is an error.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "nodes/runtime/node_args.h"

namespace p2i::runtime {

/// The type of a parameter as --help shows it: bool, int, double, string, list<T>, map<K,V>,
/// yaml (any YAML value).
template <class T>
struct ParamTypeName {
  static std::string Get() {
    if constexpr (std::is_same_v<T, bool>) return "bool";
    else if constexpr (std::is_integral_v<T>) return std::is_unsigned_v<T> ? "uint" : "int";
    else if constexpr (std::is_floating_point_v<T>) return "double";
    else if constexpr (std::is_same_v<T, std::string>) return "string";
    else return "yaml";
  }
};
template <class T>
struct ParamTypeName<std::vector<T>> {
  static std::string Get() { return "list<" + ParamTypeName<T>::Get() + ">"; }
};
template <class K, class V>
struct ParamTypeName<std::map<K, V>> {
  static std::string Get() {
    return "map<" + ParamTypeName<K>::Get() + "," + ParamTypeName<V>::Get() + ">";
  }
};

/// Parameter store of one node.
///
/// Precedence (lowest to highest): the default given to Declare(), each --params-file in command
/// line order, KEY:=VALUE overrides. Each supplied value remembers where it came from (file path
/// or "command line") so errors can say so. After the node has declared everything,
/// CheckAllDeclared() turns any supplied-but-undeclared key into a StartupError.
///
/// Thread-compatible: declare and read from the node's construction thread (normally main).
class Parameters {
 public:
  struct Info {
    std::string name;
    std::string description;
    std::string default_text;  ///< the default, as YAML flow text
    std::string value_text;    ///< the value in use, as YAML flow text
    std::string source;        ///< "default", a file path, or "command line"
    std::string type;          ///< ParamTypeName, e.g. "double", "list<int>"
  };

  Parameters() = default;
  /// Loads the files and overrides of `args`; throws StartupError for unreadable files, a file
  /// that is not a mapping, or an override whose value is not valid YAML.
  explicit Parameters(const NodeArgs& args);
  /// The same for the node `node_name` (full name `full_name`, e.g. "/ns/cam"): ROS 2
  /// parameter files pick its section (see LoadFile).
  Parameters(const NodeArgs& args, const std::string& node_name, const std::string& full_name);

  /// Adds a YAML mapping file (later calls win). Plain files map names to values. ROS 2
  /// parameter files (`NODE: {ros__parameters: {...}}`) are read as they are: the sections
  /// `/**` (every node), then the node's name, full name (`/ns/name`) or full name without the
  /// leading `/`, in file order, later ones winning; other nodes' sections are ignored.
  void LoadFile(const std::string& path);
  /// Adds KEY:=VALUE (VALUE parsed as a YAML scalar / flow sequence / flow map).
  void SetOverride(const std::string& key, const std::string& yaml_value,
                   const std::string& source = "command line");

  /// Declares `name` and returns its value (the supplied one if any, else `default_value`).
  /// T is anything yaml-cpp converts (bool, ints, double, std::string, std::vector<...>,
  /// std::map<...>, YAML::Node). Throws StartupError if the supplied value does not convert,
  /// naming the parameter, the source and the expected default.
  /// Declaring the same name twice returns the same value (the first description is kept).
  template <class T>
  T Declare(const std::string& name, const T& default_value, const std::string& description);

  /// True if a value for `name` was supplied (file or command line).
  bool IsSupplied(const std::string& name) const { return supplied_.count(name) > 0; }

  /// Throws StartupError listing every supplied parameter that was never declared, each with
  /// its source, and the declared names as a hint.
  void CheckAllDeclared() const;

  const std::map<std::string, Info>& Declared() const { return declared_; }
  /// Human-readable table of the declared parameters (for --help-params style output).
  std::string Describe() const;
  /// The --help text of the parameters: for each, "NAME (TYPE, default DEFAULT)" and its
  /// description on the next line, in declaration order.
  std::string Help() const;

 private:
  struct Supplied {
    YAML::Node value;
    std::string source;
  };
  static std::string ToFlow(const YAML::Node& node);
  void Record(const std::string& name, const std::string& description,
              const YAML::Node& default_node, const YAML::Node& value_node,
              const std::string& source, const std::string& type);
  [[noreturn]] void ThrowConversion(const std::string& name, const Supplied& s,
                                    const std::string& default_text,
                                    const std::string& what) const;

  std::string node_name_, full_name_;
  std::map<std::string, Supplied> supplied_;
  std::map<std::string, Info> declared_;
  std::vector<std::string> order_;  // declaration order (for Help())
};

template <class T>
T Parameters::Declare(const std::string& name, const T& default_value,
                      const std::string& description) {
  YAML::Node default_node;
  default_node = default_value;
  auto it = supplied_.find(name);
  if (it == supplied_.end()) {
    Record(name, description, default_node, default_node, "default", ParamTypeName<T>::Get());
    return default_value;
  }
  try {
    T value = it->second.value.template as<T>();
    Record(name, description, default_node, it->second.value, it->second.source,
           ParamTypeName<T>::Get());
    return value;
  } catch (const YAML::Exception& e) {
    ThrowConversion(name, it->second, ToFlow(default_node), e.what());
  }
}

}  // namespace p2i::runtime
