/// @file cmd_node.cc
/// @brief `p2i node list`, like `ros2 node list`: the nodes of the running graph, from the
/// discovery registry ($P2I_RUN_DIR/registry; every node registers its ~/status publisher).
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "nodes/runtime/endpoints.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunNode(const std::vector<std::string>& args) {
  CLI::App app{"Nodes of the running graph (like `ros2 node list`), from $P2I_RUN_DIR/registry.",
               "p2i node"};
  app.require_subcommand(1);
  bool verbose = false;
  auto* list = app.add_subcommand("list", "List the running nodes");
  list->add_flag("-v,--verbose", verbose, "Also print each node's pid, topics and services");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  std::map<std::string, std::vector<runtime::RegistryEntry>> nodes;
  for (const auto& e : runtime::Registry::List()) nodes[e.node].push_back(e);
  if (nodes.empty()) {
    std::fprintf(stderr,
                 "p2i node list: no running nodes in %s (start a graph with `p2i launch`, or "
                 "export the P2I_RUN_DIR that `p2i launch` prints)\n",
                 runtime::RunDir().c_str());
    return 0;
  }
  for (const auto& [node, entries] : nodes) {
    if (!verbose) {
      std::printf("%s\n", node.c_str());
      continue;
    }
    std::printf("%s (pid %d)\n", node.c_str(), entries.front().pid);
    for (const auto& e : entries)
      std::printf("  %-8s %s [%s] %s\n", e.kind == "topic" ? "publishes" : "serves",
                  e.name.c_str(), e.type.c_str(), e.endpoint.c_str());
  }
  return 0;
}

}  // namespace

P2I_COMMAND("node", "Inspect nodes: list", RunNode);

}  // namespace p2i::tools
