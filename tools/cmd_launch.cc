/// @file cmd_launch.cc
/// @brief `p2i launch FILE.yaml [name:=value ...]`: read a launch file, start its nodes.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nodes/runtime/peer_registry.h"
#include "tools/command.h"
#include "tools/launch_cleanup.h"
#include "tools/launch_machine.h"
#include "tools/launch_command.h"
#include "tools/launch_description.h"
#include "tools/launch_runner.h"

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;

constexpr const char* kUsage =
    "usage: p2i launch FILE.yaml [name:=value ...] [options]\n"
    "\n"
    "Starts the nodes of a launch file (a ROS 2 launch YAML subset, see docs/LAUNCH.md), each\n"
    "as its own process with its output prefixed by [node_name]. Ctrl-C stops them all.\n"
    "\n"
    "options:\n"
    "  --dry-run, --print     print the resolved node command lines, start nothing\n"
    "  --show-args, -s        list the file's launch arguments and exit\n"
    "  --grace-period SEC     SIGTERM -> SIGKILL delay when stopping (default 5)\n"
    "  --run-dir DIR          P2I_RUN_DIR for the nodes (default: $P2I_RUN_DIR, else a fresh\n"
    "                         /tmp/p2i-$UID/launch-<pid>, removed at exit)\n"
    "  --log-dir DIR          folder of <node>.log for nodes with output: log|both\n"
    "  --machine NAME         multi-host files: start only the nodes of `machine` NAME\n"
    "                         (default: the machine whose address is this host's)\n"
    "  -h, --help             this text\n";

struct Options {
  std::string file;
  std::vector<std::string> overrides;
  bool dry_run = false;
  bool show_args = false;
  double grace_period = 5.0;
  std::string run_dir;
  std::string log_dir;
  std::string machine;
};

// Returns -1 when parsing succeeded, else the exit code to return.
int ParseArgs(const std::vector<std::string>& args, Options* o) {
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    const auto value = [&](const char* flag) -> std::string {
      if (i + 1 >= args.size()) throw LaunchError(std::string(flag) + " needs a value");
      return args[++i];
    };
    if (a == "-h" || a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "--dry-run" || a == "--print") {
      o->dry_run = true;
    } else if (a == "--show-args" || a == "-s") {
      o->show_args = true;
    } else if (a == "--grace-period") {
      const std::string v = value("--grace-period");
      char* end = nullptr;
      o->grace_period = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(o->grace_period >= 0)) {
        throw LaunchError("--grace-period '" + v + "' must be a number of seconds >= 0");
      }
    } else if (a == "--run-dir") {
      o->run_dir = value("--run-dir");
    } else if (a == "--log-dir") {
      o->log_dir = value("--log-dir");
    } else if (a == "--machine") {
      o->machine = value("--machine");
    } else if (a.find(":=") != std::string::npos) {
      o->overrides.push_back(a);
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "p2i launch: unknown option '%s'\n\n%s", a.c_str(), kUsage);
      return 2;
    } else if (o->file.empty()) {
      o->file = a;
    } else {
      std::fprintf(stderr, "p2i launch: unexpected argument '%s' (launch arguments are "
                           "name:=value)\n", a.c_str());
      return 2;
    }
  }
  if (o->file.empty()) {
    std::fprintf(stderr, "p2i launch: no launch file given\n\n%s", kUsage);
    return 2;
  }
  return -1;
}

std::string Uid() { return std::to_string(::getuid()); }

std::string TimeStamp() {
  char buf[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(buf, sizeof(buf), "%Y%m%d-%H%M%S", std::localtime(&now));
  return buf;
}

int ShowArgs(const std::string& file) {
  const auto args = LaunchDescriptionReader::ListArguments(file);
  if (args.empty()) std::printf("%s declares no launch arguments\n", file.c_str());
  for (const auto& a : args) {
    std::printf("'%s':\n    %s\n    (%s)\n", a.name.c_str(),
                a.description.empty() ? "no description given" : a.description.c_str(),
                a.has_default ? ("default: '" + a.default_value + "'").c_str() : "required");
  }
  return 0;
}

std::string CommandLine(const std::vector<std::string>& argv) {
  std::string line;
  for (const auto& a : argv) line += (line.empty() ? "" : " ") + ShellQuote(a);
  return line;
}

// --dry-run: a node's command line, flags and inline parameter files as comments.
void PrintDryRunNode(const NodeDescription& node, const NodeCommand& cmd) {
  std::string flags;
  if (node.required) flags += ", required";
  if (node.respawn) {
    char delay[32];
    std::snprintf(delay, sizeof(delay), "%g", node.respawn_delay);
    flags += std::string(", respawn after ") + delay + " s";
  }
  if (node.output != "screen") flags += ", output " + node.output;
  std::printf("# [%s] %s%s\n%s\n", cmd.display_name.c_str(), node.source.c_str(), flags.c_str(),
              CommandLine(cmd.argv).c_str());
  for (const auto& [path, text] : cmd.param_files) {
    std::printf("#   %s:\n", path.c_str());
    size_t start = 0, nl;
    while ((nl = text.find('\n', start)) != std::string::npos) {
      std::printf("#     %s\n", text.substr(start, nl - start).c_str());
      start = nl + 1;
    }
  }
}

// The processes to start, one per node, with their parameter files written to params_dir.
struct NodeProcesses {
  std::vector<ProcessSpec> specs;
  std::string missing;  // one line per node whose executable was not found
  bool any_param_file = false;
};

NodeProcesses BuildProcesses(const LaunchDescription& description, const std::string& params_dir,
                             bool dry_run) {
  const std::string self_dir = SelfDir();
  NodeProcesses out;
  for (size_t i = 0; i < description.nodes.size(); ++i) {
    const NodeDescription& node = description.nodes[i];
    std::string searched;
    std::string exe = FindNodeExecutable(node.exec, self_dir, &searched);
    if (exe.empty()) {
      out.missing += "  " + node.source + ": node '" + node.DisplayName() + "': exec '" +
                     node.exec + "' not found (looked for " + searched + ")\n";
      exe = "p2i_" + node.exec;
    }
    const NodeCommand cmd = BuildNodeCommand(node, exe, params_dir, static_cast<int>(i));
    WriteParamFiles(cmd);
    out.any_param_file = out.any_param_file || !cmd.param_files.empty();
    if (dry_run) PrintDryRunNode(node, cmd);
    ProcessSpec spec;
    spec.name = cmd.display_name;
    spec.argv = cmd.argv;
    spec.respawn = node.respawn;
    spec.respawn_delay = node.respawn_delay;
    spec.required = node.required;
    spec.output = node.output;
    out.specs.push_back(std::move(spec));
  }
  return out;
}

// One run dir per launch unless the user chose one, so every node (and `p2i topic` given
// the same P2I_RUN_DIR) derives the same ipc:// endpoints, and two launches never collide.
// Sets P2I_RUN_DIR; *own says whether the launch made it (and removes it at exit).
std::string PrepareRunDir(const Options& o, bool* own) {
  *own = false;
  std::string run_dir = o.run_dir;
  if (run_dir.empty()) {
    const char* env = std::getenv("P2I_RUN_DIR");
    if (env != nullptr && *env != '\0') {
      run_dir = env;
    } else {
      run_dir = "/tmp/p2i-" + Uid() + "/launch-" + std::to_string(::getpid());
      *own = true;
    }
  }
  fs::create_directories(run_dir);
  fs::permissions(run_dir, fs::perms::owner_all, fs::perm_options::replace);
  ::setenv("P2I_RUN_DIR", run_dir.c_str(), 1);
  std::fprintf(stderr, "[launch] P2I_RUN_DIR=%s%s\n", run_dir.c_str(),
               *own ? " (`p2i topic` finds it; export it to look at this launch only)" : "");
  return run_dir;
}

// The nodes' OpenMP threads sleep when they wait (libgomp reads OMP_WAIT_POLICY once, when it
// loads, so only the parent can set it). With the default (spin, then sleep) a 2-thread trainer
// beside other busy processes was 2-10x slower than 1 thread; passive was as fast as 1 thread or
// faster (docs/MODEL.md "Benchmark", issue 11 point 2). A value the user exported is kept.
void SetThreadingDefaults() {
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", /*overwrite=*/0);
}

// Multi-host files: this host's registry, and the environment the nodes find their peers by.
std::unique_ptr<runtime::RegistryServer> StartRegistry(const MachinePlan& plan) {
  if (!plan.multi_host) return nullptr;
  ::setenv("P2I_HOST_ADDRESS", plan.self.address.c_str(), 1);
  ::setenv("P2I_PEERS", plan.PeersText().c_str(), 1);
  auto server = std::make_unique<runtime::RegistryServer>(plan.self.RegistryEndpoint());
  std::fprintf(stderr, "[launch] registry of this host at %s\n", server->Endpoint().c_str());
  return server;
}

// Runs the processes until the launch ends; removes the launch's folders whatever happens.
int RunProcesses(std::vector<ProcessSpec> specs, const Options& o, const std::string& params_dir,
                 const std::string& run_dir, bool own_run_dir) {
  LaunchRunnerOptions runner_options;
  runner_options.grace_period = o.grace_period;
  runner_options.log_dir = !o.log_dir.empty()
                               ? o.log_dir
                               : "/tmp/p2i-" + Uid() + "/log/launch-" + TimeStamp() + "-" +
                                     std::to_string(::getpid());
  int code = 1;
  try {
    LaunchRunner runner(std::move(specs), runner_options);
    code = runner.Run();
  } catch (...) {
    fs::remove_all(params_dir);
    if (own_run_dir) fs::remove_all(run_dir);
    throw;
  }
  std::error_code ec;
  fs::remove_all(params_dir, ec);
  if (own_run_dir) fs::remove_all(run_dir, ec);
  std::fprintf(stderr, "[launch] done, exit code %d\n", code);
  return code;
}

int RunLaunch(const std::vector<std::string>& args) {
  Options o;
  const int parse = ParseArgs(args, &o);
  if (parse >= 0) return parse;
  if (o.show_args) return ShowArgs(o.file);

  LaunchDescription description =
      LaunchDescriptionReader::ReadFile(o.file, ParseLaunchOverrides(o.overrides));
  // Multi-host files: only this machine's part, wired to the other machines' registries.
  const MachinePlan plan = PlanMachine(description, o.machine);
  if (plan.multi_host) {
    std::fprintf(stderr, "[launch] machine %s (%s): %zu of %zu nodes; peers %s\n",
                 plan.self.name.c_str(), plan.self.address.c_str(), plan.nodes.size(),
                 description.nodes.size(), plan.PeersText().c_str());
    description.nodes = plan.nodes;
  }
  if (description.nodes.empty()) {
    std::fprintf(stderr, "[launch] %s starts no nodes\n", o.file.c_str());
    return 0;
  }
  // Launches killed with SIGKILL could not clean up: remove their folders now.
  if (!o.dry_run) {
    for (const auto& dir : RemoveStaleLaunchDirs("/tmp/p2i-" + Uid()))
      std::fprintf(stderr, "[launch] removed %s (left by a launcher that is no longer running)\n",
                   dir.c_str());
  }
  const std::string params_dir = MakeLaunchParamsDir();
  NodeProcesses processes = BuildProcesses(description, params_dir, o.dry_run);
  if (!processes.missing.empty()) {
    std::fprintf(stderr, "p2i launch: executables not found:\n%s(build them, or put them on "
                         "$PATH)\n", processes.missing.c_str());
    if (!o.dry_run || !processes.any_param_file) fs::remove_all(params_dir);
    return 2;  // a configuration error: nothing started
  }
  if (o.dry_run) {
    if (processes.any_param_file) {
      std::printf("# inline parameter files are kept in %s\n", params_dir.c_str());
    } else {
      fs::remove_all(params_dir);
    }
    return 0;
  }
  bool own_run_dir = false;
  const std::string run_dir = PrepareRunDir(o, &own_run_dir);
  SetThreadingDefaults();
  const std::unique_ptr<runtime::RegistryServer> registry_server = StartRegistry(plan);
  return RunProcesses(std::move(processes.specs), o, params_dir, run_dir, own_run_dir);
}

}  // namespace
}  // namespace p2i::tools

P2I_COMMAND("launch", "Start nodes from a launch YAML file (ROS 2 launch subset)",
            p2i::tools::RunLaunch);
