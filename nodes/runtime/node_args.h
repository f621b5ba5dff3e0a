/// @file node_args.h
/// @brief The node command line (see the node CLI contract): name, namespace, parameter files,
/// remappings, KEY:=VALUE overrides and extra arguments.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace p2i::runtime {

/// Thrown for a malformed command line or an unknown/ill-typed parameter. Nodes exit with code 2
/// when they catch it (see RunNode()).
class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What `p2i_<exec> [--name N] [--namespace NS] [--params-file F]... [-r FROM:=TO]...
/// [KEY:=VALUE]... [--help] [--version]` says. ROS 2 spellings are accepted too: `--ros-args`
/// (ignored), `-p KEY:=VALUE`, `--remap`. Any other token is a StartupError (a `rate=10`
/// silently ignored would run the node with the default). A plain value type; thread-compatible.
struct NodeArgs {
  std::string name;                 ///< empty = the executable's default name
  std::string node_namespace = "/";
  std::vector<std::string> params_files;                       ///< applied in order
  std::vector<std::pair<std::string, std::string>> remaps;     ///< FROM, TO as written
  std::vector<std::pair<std::string, std::string>> overrides;  ///< KEY, VALUE (YAML text)
  std::vector<std::string> extra;   ///< always empty (kept for source compatibility)
  bool help = false;                ///< -h / --help: print the declared parameters and exit 0
  bool version = false;             ///< --version: print the version and exit 0

  /// Parses argv[1..]; throws StartupError naming the offending argument (and, for KEY=VALUE,
  /// suggesting KEY:=VALUE).
  static NodeArgs Parse(int argc, const char* const* argv);
  static NodeArgs Parse(const std::vector<std::string>& args);  ///< args without argv[0]
};

}  // namespace p2i::runtime
