/// @file launch_command.h
/// @brief From a NodeDescription to the process command line of the node CLI contract.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "tools/launch_description.h"

namespace p2i::tools {

/// A node ready to start: its argv (argv[0] = executable path) and the inline parameter files
/// that argv refers to (path, YAML content), which must be written before the process starts.
struct NodeCommand {
  std::string display_name;
  std::vector<std::string> argv;
  std::vector<std::pair<std::string, std::string>> param_files;
};

/// Builds `EXE [--name N] --namespace NS [--params-file F]... [-r FROM:=TO]... [args...]`.
/// Consecutive inline `param` entries share one file `<params_dir>/<index>_<name>.<k>.yaml`, so
/// files and inline values apply in the order the launch file lists them.
NodeCommand BuildNodeCommand(const NodeDescription& node, const std::string& executable,
                             const std::string& params_dir, int index);

/// Finds the executable of `exec`: p2i_<exec> in `self_dir` (the folder of the `p2i` binary),
/// then p2i_<exec> and <exec> on $PATH. Returns "" when none exists and, if `searched` is
/// given, describes where it looked.
std::string FindNodeExecutable(const std::string& exec, const std::string& self_dir,
                               std::string* searched = nullptr);

/// The folder of the running executable (/proc/self/exe).
std::string SelfDir();

/// `word` quoted for a POSIX shell when it needs it (for printing command lines).
std::string ShellQuote(const std::string& word);

/// Writes the parameter files of `command` (creating their folder); throws std::runtime_error.
void WriteParamFiles(const NodeCommand& command);

}  // namespace p2i::tools
