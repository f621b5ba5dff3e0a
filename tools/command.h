/// @file command.h
/// @brief Subcommands of the `p2i` tool register themselves here (like `ros2 <verb>`).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace p2i::tools {

/// A subcommand gets its own name in args[0] followed by its arguments, and returns the
/// process exit code.
using CommandFn = std::function<int(const std::vector<std::string>& args)>;

struct Command {
  std::string summary;
  CommandFn run;
};

/// The registry, filled by static P2I_COMMAND registrations before main() runs.
inline std::map<std::string, Command>& Commands() {
  static std::map<std::string, Command> commands;
  return commands;
}

struct CommandRegistration {
  CommandRegistration(const std::string& name, const std::string& summary, CommandFn fn) {
    Commands()[name] = Command{summary, std::move(fn)};
  }
};

}  // namespace p2i::tools

#define P2I_CONCAT_INNER(a, b) a##b
#define P2I_CONCAT(a, b) P2I_CONCAT_INNER(a, b)
/// P2I_COMMAND("launch", "Start nodes from a launch YAML file", RunLaunch);
#define P2I_COMMAND(name, summary, fn) \
  static ::p2i::tools::CommandRegistration P2I_CONCAT(p2i_command_, __LINE__)(name, summary, fn)
