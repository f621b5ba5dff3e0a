/// @file launch_description.h
/// @brief A ROS 2 launch YAML subset read into the list of nodes to start (no processes here).
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tools/launch_error.h"

namespace p2i::tools {

/// One `param:` entry of a node: either a parameter file (`from:`) or one inline parameter
/// whose value is YAML text (scalar, flow sequence or flow map) after substitution.
struct LaunchParam {
  std::string from_file;   ///< absolute path; non-empty for a `from:` entry
  std::string name;        ///< inline parameter name
  std::string value_yaml;  ///< inline value, YAML flow text (types inferred by the node)
  std::string source;      ///< "FILE:LINE" of the entry (named by the node's errors)
  bool IsFile() const { return !from_file.empty(); }
};

/// One node to start, fully resolved (substitutions done, namespace absolute). A value type.
struct NodeDescription {
  std::string pkg;             ///< accepted for ROS compatibility, not used to find the exec
  std::string exec;            ///< p2i_<exec> is the executable
  std::string name;            ///< empty = the executable's default name
  std::string node_namespace = "/";
  std::vector<LaunchParam> params;                          ///< in file order
  std::vector<std::pair<std::string, std::string>> remaps;  ///< FROM, TO
  std::vector<std::string> args;                            ///< `args:` split like a shell
  bool respawn = false;
  double respawn_delay = 0.0;  ///< seconds
  std::string output = "screen";  ///< screen | log | both
  bool required = false;
  std::string machine;         ///< `machine:` name (multi-host launch files), "" = none
  std::string source;          ///< "FILE:LINE" of the `node:` entry, for messages

  /// The name used in output prefixes and messages: `name`, else `exec`.
  std::string DisplayName() const { return name.empty() ? exec : name; }
};

/// One `arg` declaration, as written (for `p2i launch FILE --show-args`).
struct LaunchArgument {
  std::string name;
  std::string default_value;
  bool has_default = false;
  std::string description;
  std::string source;  ///< "FILE:LINE"
};

/// One `machine` entity (as roslaunch's <machine>): a host of a multi-host graph.
struct MachineDescription {
  std::string name;
  std::string address;         ///< IP address (or name) other hosts reach it at
  int discovery_port = 7411;   ///< its launcher's registry server: tcp://address:port
  std::string source;          ///< "FILE:LINE"
  std::string RegistryEndpoint() const {
    return "tcp://" + address + ":" + std::to_string(discovery_port);
  }
};

/// Everything a launch file (and its includes) asks for.
struct LaunchDescription {
  std::vector<NodeDescription> nodes;        ///< in file order, includes expanded in place
  std::vector<MachineDescription> machines;  ///< `machine` entities; every node then names one
  std::vector<LaunchArgument> arguments;     ///< every `arg` met, top file first
  std::map<std::string, std::string> top_level_vars;  ///< variables of the top file at its end
};

/// Reads launch YAML:
///
///   launch:
///   - arg: {name: rate, default: "30", description: "frames/s"}
///   - let: {name: ns, value: "robot"}
///   - include: {file: "$(dirname)/other.yaml", arg: [{name: x, value: "1"}]}
///   - group:                      # or {namespace: NS, children: [...]}
///     - push-ros-namespace: {namespace: "$(var ns)"}
///     - node: {exec: camera, name: cam, param: [{name: rate, value: "$(var rate)"}]}
///
/// Command-line `name:=value` overrides set launch variables before the top file is read, so
/// they win over `arg` defaults in every file; an override that no `arg` declares is an error.
/// Relative `include` files and `param: from:` files resolve against the including file's
/// folder. Every error is a LaunchError naming file, line and key. Stateless; thread-safe.
class LaunchDescriptionReader {
 public:
  /// Reads `path` and its includes.
  static LaunchDescription ReadFile(const std::string& path,
                                    const std::map<std::string, std::string>& overrides = {});
  /// Same for YAML text; `path` is its nominal location (for `$(dirname)`, relative paths and
  /// messages).
  static LaunchDescription ReadString(const std::string& text, const std::string& path,
                                      const std::map<std::string, std::string>& overrides = {});
  /// The `arg` declarations of the top file only, without evaluating anything else.
  static std::vector<LaunchArgument> ListArguments(const std::string& path);
};

/// Parses `name:=value` command-line words; throws LaunchError for a word without ":=" or an
/// empty name.
std::map<std::string, std::string> ParseLaunchOverrides(const std::vector<std::string>& words);

/// Splits an `args:` string like a POSIX shell would (whitespace, '...' and "..." quoting,
/// backslash escapes); throws std::invalid_argument on an unterminated quote.
std::vector<std::string> SplitShellWords(const std::string& text);

/// "/" joined with the pushed namespace and a node's own `namespace:`; absolute ones replace.
std::string JoinNamespace(const std::string& base, const std::string& ns);

}  // namespace p2i::tools
