/// @file graph_discovery.cc
#include "nodes/runtime/graph_discovery.h"

#include <cstdlib>

#include "nodes/runtime/peer_registry.h"

namespace p2i::runtime {

std::vector<std::string> DiscoveryRunDirs() {
  const char* env = std::getenv("P2I_RUN_DIR");
  if (env && *env) return {RunDir()};
  return Registry::UserRunDirs();
}

std::string DiscoveryPlaces(const std::vector<std::string>& peers) {
  std::string out;
  for (const auto& dir : DiscoveryRunDirs()) out += (out.empty() ? "" : ", ") + dir;
  return peers.empty() ? out : out + " or on the peers";
}

std::vector<RegistryEntry> DiscoverGraph(const std::vector<std::string>& peers,
                                         std::chrono::milliseconds timeout,
                                         std::vector<std::string>* errors) {
  return ListGraph(DiscoveryRunDirs(), peers, timeout, errors);
}

}  // namespace p2i::runtime
