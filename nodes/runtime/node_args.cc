/// @file node_args.cc
/// @brief Parsing of the node command line.
#include "nodes/runtime/node_args.h"

namespace p2i::runtime {

NodeArgs NodeArgs::Parse(int argc, const char* const* argv) {
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  return Parse(args);
}

NodeArgs NodeArgs::Parse(const std::vector<std::string>& args) {
  NodeArgs out;
  auto need_value = [&](size_t i, const std::string& flag) -> const std::string& {
    if (i + 1 >= args.size()) {
      throw StartupError("command line: '" + flag + "' needs a value (e.g. " + flag +
                         (flag == "-r" ? " from:=to)" : " VALUE)"));
    }
    return args[i + 1];
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    std::string value;
    auto take = [&](const std::string& flag) -> bool {
      if (a == flag) {
        value = need_value(i, flag);
        ++i;
        return true;
      }
      if (flag.size() > 2 && a.rfind(flag + "=", 0) == 0) {
        value = a.substr(flag.size() + 1);
        return true;
      }
      return false;
    };
    if (take("--name")) {
      out.name = value;
    } else if (take("--namespace")) {
      out.node_namespace = value;
    } else if (take("--params-file")) {
      out.params_files.push_back(value);
    } else if (take("-r") || take("--remap")) {
      const auto pos = value.find(":=");
      if (pos == std::string::npos || pos == 0 || pos + 2 == value.size()) {
        throw StartupError("command line: remapping '" + value + "' must be FROM:=TO");
      }
      out.remaps.emplace_back(value.substr(0, pos), value.substr(pos + 2));
    } else if (take("-p")) {  // ROS 2: -p KEY:=VALUE
      const auto pos = value.find(":=");
      if (pos == std::string::npos || pos == 0)
        throw StartupError("command line: '-p " + value + "' must be -p NAME:=VALUE");
      out.overrides.emplace_back(value.substr(0, pos), value.substr(pos + 2));
    } else if (a == "-h" || a == "--help") {
      out.help = true;
    } else if (a == "--version") {
      out.version = true;
    } else if (a == "--ros-args" || a == "--") {
      // ROS 2 marks its arguments with --ros-args [...] --: accepted, nothing to do.
    } else if (a.find(":=") != std::string::npos && a.rfind("-", 0) != 0) {
      const auto pos = a.find(":=");
      if (pos == 0) throw StartupError("command line: override '" + a + "' has no key");
      out.overrides.emplace_back(a.substr(0, pos), a.substr(pos + 2));
    } else {
      std::string hint;
      const auto eq = a.find('=');
      if (eq != std::string::npos && eq > 0 && a[0] != '-')
        hint = " (did you mean " + a.substr(0, eq) + ":=" + a.substr(eq + 1) + "?)";
      throw StartupError("command line: '" + a + "' is neither NAME:=VALUE nor one of --name, "
                         "--namespace, --params-file, -r, -p, --help, --version" + hint +
                         "; see --help");
    }
  }
  if (out.node_namespace.empty()) out.node_namespace = "/";
  return out;
}

}  // namespace p2i::runtime
