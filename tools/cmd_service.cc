/// @file cmd_service.cc
/// @brief `p2i service list | call NAME TYPE VALUE`, like `ros2 service`: services of the
/// running graph (found as `p2i topic` finds topics: runtime::DiscoverGraph, --peer) and one
/// call with a request written as YAML/JSON.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/raw_service.h"
#include "nodes/runtime/shutdown.h"
#include "tools/cli_exit.h"
#include "tools/command.h"
#include "tools/graph_json.h"

namespace p2i::tools {
namespace {

std::string Absolute(const std::string& name) {
  return name.empty() || name[0] == '/' ? name : "/" + name;
}

// The services of the discovered graph (warnings for unreachable places on stderr).
std::vector<runtime::RegistryEntry> DiscoverServices(const std::vector<std::string>& peers,
                                                     const char* what) {
  std::vector<runtime::RegistryEntry> services;
  std::vector<std::string> errors;
  for (auto& e : runtime::DiscoverGraph(peers, std::chrono::milliseconds(1000), &errors))
    if (e.kind == "service") services.push_back(std::move(e));
  for (const auto& e : errors) std::fprintf(stderr, "%s: warning: %s\n", what, e.c_str());
  return services;
}

int PrintServices(const std::vector<runtime::RegistryEntry>& services, bool types,
                  const std::vector<std::string>& peers) {
  std::vector<std::string> printed;
  for (const auto& e : services) {
    const std::string line = types ? e.name + " [" + e.type + "]" : e.name;
    if (std::find(printed.begin(), printed.end(), line) != printed.end()) continue;
    printed.push_back(line);
    std::printf("%s\n", line.c_str());
  }
  if (services.empty()) {
    std::fprintf(stderr, "p2i service list: no services in %s (is a graph running?)\n",
                 runtime::DiscoveryPlaces(peers).c_str());
  }
  return 0;
}

// The endpoint to call `name` at: the first reachable registered server ("" = its default
// endpoint). Throws std::invalid_argument when the service takes another request type.
std::string FindServer(const std::vector<runtime::RegistryEntry>& services, const std::string& name,
                       const std::string& type, const std::vector<std::string>& peers,
                       const char* what) {
  for (const auto& e : services) {
    if (e.name != name) continue;
    if (e.type != type)
      throw std::invalid_argument("service " + name + " takes " + e.type + ", not " + type);
  }
  // Local servers first, then the peers' tcp endpoints (remote ipc paths are unreachable).
  const auto endpoints = runtime::ReachableEndpoints(services, "service", name);
  if (endpoints.size() > 1) {
    std::fprintf(stderr, "%s: warning: %zu servers of %s; calling the first (--endpoint picks "
                         "one):", what, endpoints.size(), name.c_str());
    for (const auto& ep : endpoints) std::fprintf(stderr, " %s", ep.c_str());
    std::fprintf(stderr, "\n");
  }
  if (!endpoints.empty()) return endpoints.front();
  std::fprintf(stderr,
               "%s: warning: no server of %s registered in %s; trying its default endpoint\n",
               what, name.c_str(), runtime::DiscoveryPlaces(peers).c_str());
  return "";
}

// One call of `name` with the request `value` of type t; prints the reply.
int CallService(const std::string& name, msgs::pb::MsgType t, const std::string& value,
                const std::string& endpoint, double timeout_s) {
  runtime::ServiceClientOptions o;
  o.endpoint = endpoint;
  o.timeout = std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000));
  o.retries = 0;
  runtime::RawServiceClient client(name, o);
  auto msg = MessageFromText(t, value, "/p2i_service_call_" + std::to_string(::getpid()));
  StampHeader(msg.get(), client.NextRequestId(), client.NextRequestId());
  msgs::WireMessage request;
  request.header = msg->SerializeAsString();
  msgs::WireMessage reply;
  std::string error;
  std::printf("requester: making request to %s (%s)\n", name.c_str(), client.Endpoint().c_str());
  if (!client.Call(request, &reply, &error)) {
    std::fprintf(stderr, "p2i service call: %s\n", error.c_str());
    return 1;
  }
  std::string text = msgs::DebugString(reply);
  std::printf("response:\n%s", text.c_str());
  return 0;
}

int RunService(const std::vector<std::string>& args) {
  CLI::App app{"Services of the running graph (like `ros2 service`), found as `p2i topic list` "
               "finds topics: $P2I_RUN_DIR/registry, else every running launch of this user, and "
               "the registries of other hosts (--peer, $P2I_PEERS; docs/MULTIHOST.md).",
               "p2i service"};
  app.require_subcommand(1);
  bool types = false;
  auto* list = app.add_subcommand("list", "List the services of running nodes");
  list->add_flag("-t,--show-types", types, "Also print each service's request type");
  std::string name, type, value, endpoint;
  double timeout_s = 5.0;
  auto* call = app.add_subcommand("call", "Call a service once and print the reply");
  call->add_option("service", name, "Service name (absolute, or relative to /)")->required();
  call->add_option("type", type, "Request type, e.g. RenderRequest")->required();
  call->add_option("value", value, "The request as YAML/JSON (fields of msgs/p2i.proto), e.g. "
                                   "'{poses: [{position: {z: 1}, orientation: {w: 1}}]}'");
  call->add_option("--endpoint", endpoint, "Call here instead of the discovered endpoint");
  call->add_option("--timeout", timeout_s, "Seconds to wait for the reply")
      ->check(CLI::PositiveNumber);
  std::vector<std::string> peers = runtime::PeerRegistries();
  for (auto* sub : {list, call}) {
    sub->add_option("--peer", peers,
                    "Registry of another host's launch, tcp://ADDRESS:PORT (repeatable; "
                    "default $P2I_PEERS)");
  }
  std::vector<std::string> rest(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rest);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  runtime::Shutdown::InstallSignalHandlers();
  const char* what = list->parsed() ? "p2i service list" : "p2i service call";
  std::vector<runtime::RegistryEntry> services;
  if (list->parsed() || endpoint.empty()) services = DiscoverServices(peers, what);
  if (list->parsed()) return PrintServices(services, types, peers);
  name = Absolute(name);
  const msgs::pb::MsgType t = MsgTypeFromName(type);
  if (endpoint.empty()) endpoint = FindServer(services, name, type, peers, what);
  return CallService(name, t, value, endpoint, timeout_s);
}

}  // namespace

P2I_COMMAND("service", "Inspect and call services: list | call NAME TYPE VALUE", RunService);

}  // namespace p2i::tools
