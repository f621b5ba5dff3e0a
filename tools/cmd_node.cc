/// @file cmd_node.cc
/// @brief `p2i node list`, like `ros2 node list`: the nodes of the running graph, from the
/// discovery registries (every node registers its ~/status publisher) that DiscoverGraph reads:
/// $P2I_RUN_DIR, else every running launch of this user, plus --peer / $P2I_PEERS.
#include <chrono>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/peer_registry.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunNode(const std::vector<std::string>& args) {
  CLI::App app{"Nodes of the running graph (like `ros2 node list`), found as `p2i topic list` "
               "finds topics: $P2I_RUN_DIR/registry, else every running launch of this user, and "
               "the registries of other hosts (--peer, $P2I_PEERS; docs/MULTIHOST.md).",
               "p2i node"};
  app.require_subcommand(1);
  bool verbose = false;
  std::vector<std::string> peers = runtime::PeerRegistries();
  auto* list = app.add_subcommand("list", "List the running nodes");
  list->add_flag("-v,--verbose", verbose, "Also print each node's pid, topics and services");
  list->add_option("--peer", peers,
                   "Registry of another host's launch, tcp://ADDRESS:PORT (repeatable; default "
                   "$P2I_PEERS)");
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  std::vector<std::string> errors;
  std::map<std::string, std::vector<runtime::RegistryEntry>> nodes;
  for (const auto& e : runtime::DiscoverGraph(peers, std::chrono::milliseconds(1000), &errors))
    nodes[e.node].push_back(e);
  for (const auto& e : errors) std::fprintf(stderr, "p2i node list: warning: %s\n", e.c_str());
  if (nodes.empty()) {
    std::fprintf(stderr,
                 "p2i node list: no running nodes in %s (start a graph with `p2i launch`)\n",
                 runtime::DiscoveryPlaces(peers).c_str());
    return 0;
  }
  for (const auto& [node, entries] : nodes) {
    if (!verbose) {
      std::printf("%s\n", node.c_str());
      continue;
    }
    const auto& first = entries.front();
    std::printf("%s (pid %d%s%s)\n", node.c_str(), first.pid, first.host.empty() ? "" : ", via ",
                first.host.c_str());
    for (const auto& e : entries)
      std::printf("  %-8s %s [%s] %s\n", e.kind == "topic" ? "publishes" : "serves",
                  e.name.c_str(), e.type.c_str(), e.endpoint.c_str());
  }
  return 0;
}

}  // namespace

P2I_COMMAND("node", "Inspect nodes: list", RunNode);

}  // namespace p2i::tools
