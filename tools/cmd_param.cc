/// @file cmd_param.cc
/// @brief `p2i param list [NODE] | get NODE NAME | set NODE NAME VALUE`, like `ros2 param`, on
/// running nodes through their parameter files (nodes/runtime/param_service.h) in the params/
/// folder of each run dir discovery reads (runtime::DiscoveryRunDirs(): $P2I_RUN_DIR, else
/// every running launch of this user). This host only: parameter files are not served to other
/// hosts. `set` works for parameters the node declares dynamic (every node's log_level; see
/// `p2i param list NODE`).
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <yaml-cpp/yaml.h>

#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/param_service.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

namespace fs = std::filesystem;

struct NodeParams {
  std::string node;
  int pid = 0;
  std::string stem;  // path without extension
  YAML::Node params;
};

std::string Places() {
  std::string out;
  for (const auto& dir : runtime::DiscoveryRunDirs())
    out += (out.empty() ? "" : ", ") + runtime::ParamsDir(dir);
  return out;
}

// The nodes with parameter files in one params/ folder.
void RunningIn(const std::string& params_dir, std::vector<NodeParams>* out) {
  std::error_code ec;
  for (fs::directory_iterator it(params_dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().extension() != ".yaml") continue;
    try {
      const YAML::Node y = YAML::LoadFile(it->path().string());
      NodeParams n;
      n.node = y["node"].as<std::string>();
      n.pid = y["pid"].as<int>();
      if (::kill(n.pid, 0) != 0 && errno == ESRCH) continue;  // a node killed with SIGKILL
      n.stem = (it->path().parent_path() / it->path().stem()).string();
      n.params = y["parameters"];
      out->push_back(n);
    } catch (const std::exception&) {
      // being rewritten or foreign: skip
    }
  }
}

std::vector<NodeParams> Running() {
  std::vector<NodeParams> out;
  for (const auto& dir : runtime::DiscoveryRunDirs()) RunningIn(runtime::ParamsDir(dir), &out);
  return out;
}

std::string Absolute(const std::string& n) { return n.empty() || n[0] == '/' ? n : "/" + n; }

// The one running node called `node`; two of that name (two launches) are refused with where
// each lives, as changing one at random would be.
NodeParams Find(const std::string& node) {
  std::string names;
  std::vector<NodeParams> found;
  for (auto& n : Running()) {
    if (n.node == Absolute(node)) found.push_back(n);
    names += " " + n.node;
  }
  if (found.size() == 1) return found.front();
  if (found.size() > 1) {
    std::string where;
    for (const auto& n : found)
      where += " " + fs::path(n.stem).parent_path().parent_path().string() + " (pid " +
               std::to_string(n.pid) + ")";
    throw std::invalid_argument(std::to_string(found.size()) + " running nodes are called " +
                                Absolute(node) + ", in" + where +
                                ": export P2I_RUN_DIR=<one of those run dirs> to pick one");
  }
  throw std::invalid_argument("no running node '" + Absolute(node) + "' in " + Places() +
                              (names.empty() ? " (is a graph running? p2i node list)"
                                             : " (running:" + names + ")"));
}

int ListParams(const std::string& node, bool describe) {
  std::vector<NodeParams> nodes = node.empty() ? Running() : std::vector<NodeParams>{Find(node)};
  if (nodes.empty()) std::fprintf(stderr, "p2i param list: no running nodes in %s\n", Places().c_str());
  for (const auto& n : nodes) {
    std::printf("%s:\n", n.node.c_str());
    for (const auto& kv : n.params) {
      const YAML::Node p = kv.second;
      if (!describe) {
        std::printf("  %s\n", kv.first.as<std::string>().c_str());
        continue;
      }
      std::printf("  %s (%s, default %s%s): %s\n", kv.first.as<std::string>().c_str(),
                  p["type"].as<std::string>().c_str(), p["default"].as<std::string>().c_str(),
                  p["dynamic"].as<bool>() ? ", dynamic" : "",
                  p["description"].as<std::string>().c_str());
    }
  }
  return 0;
}

// Asks the node to set a dynamic parameter (NODE.set, written atomically) and waits up to 5 s
// for its NODE.result.
int SetParam(const NodeParams& n, const std::string& name, const std::string& value) {
  if (!n.params[name]["dynamic"].as<bool>()) {
    std::fprintf(stderr, "p2i param set: parameter '%s' of %s is not dynamic (read at start-up "
                         "only: restart the node with %s:=VALUE)\n",
                 name.c_str(), n.node.c_str(), name.c_str());
    return 1;
  }
  std::remove((n.stem + ".result").c_str());
  {
    YAML::Emitter req;
    req << YAML::BeginMap << YAML::Key << "name" << YAML::Value << name << YAML::Key << "value"
        << YAML::Value << YAML::Load(value) << YAML::EndMap;
    std::ofstream out(n.stem + ".set.tmp");
    out << req.c_str() << "\n";
  }
  std::rename((n.stem + ".set.tmp").c_str(), (n.stem + ".set").c_str());
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < end) {
    std::ifstream in(n.stem + ".result");
    if (in) {
      std::stringstream s;
      s << in.rdbuf();
      std::string r = s.str();
      while (!r.empty() && r.back() == '\n') r.pop_back();
      if (r == "ok") {
        std::printf("Set parameter successful\n");
        return 0;
      }
      std::fprintf(stderr, "p2i param set: %s\n", r.c_str());
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::fprintf(stderr, "p2i param set: %s did not answer within 5 s\n", n.node.c_str());
  return 1;
}

int RunParam(const std::vector<std::string>& args) {
  CLI::App app{"Parameters of running nodes (like `ros2 param`): the nodes of $P2I_RUN_DIR, else "
               "of every running launch of this user (this host only).",
               "p2i param"};
  app.require_subcommand(1);
  std::string node, name, value;
  bool describe = false;
  auto* list = app.add_subcommand("list", "List the parameters of one node or of every node");
  list->add_option("node", node, "Full node name, e.g. /pose_source");
  list->add_flag("-d,--describe", describe, "Also print type, default, dynamic, description");
  auto* get = app.add_subcommand("get", "Print a parameter's value");
  get->add_option("node", node, "Full node name")->required();
  get->add_option("name", name, "Parameter name")->required();
  auto* set = app.add_subcommand("set", "Set a dynamic parameter of a running node");
  set->add_option("node", node, "Full node name")->required();
  set->add_option("name", name, "Parameter name")->required();
  set->add_option("value", value, "New value (YAML)")->required();
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  if (list->parsed()) return ListParams(node, describe);
  const NodeParams n = Find(node);
  if (!n.params[name]) {
    std::string names;
    for (const auto& kv : n.params) names += " " + kv.first.as<std::string>();
    throw std::invalid_argument("node " + n.node + " has no parameter '" + name +
                                "' (its parameters:" + names + ")");
  }
  if (get->parsed()) {
    std::printf("%s\n", n.params[name]["value"].as<std::string>().c_str());
    return 0;
  }
  return SetParam(n, name, value);
}

}  // namespace

P2I_COMMAND("param", "Parameters of running nodes: list | get NODE NAME | set NODE NAME VALUE",
            RunParam);

}  // namespace p2i::tools
