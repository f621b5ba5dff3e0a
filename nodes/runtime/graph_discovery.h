/// @file graph_discovery.h
/// @brief Where tools that join a running graph from outside it (`p2i topic`, `p2i node`,
/// `p2i service`, `p2i param` (local run dirs only), `p2i record -a`, p2i_foxglove_bridge;
/// python/p2i_client.py applies the same rule) look for its nodes, topics and services: the way
/// `ros2 topic list` finds a running graph without anything exported.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "nodes/runtime/endpoints.h"

namespace p2i::runtime {

/// The local run dirs discovery reads: {$P2I_RUN_DIR} when it is set (the nodes of a launch,
/// or a shell that exported it), else Registry::UserRunDirs(): /tmp/p2i-$UID and every
/// /tmp/p2i-$UID/launch-* that `p2i launch` made for a running launch.
std::vector<std::string> DiscoveryRunDirs();

/// Where discovery looked, for "found nothing" messages: the DiscoveryRunDirs() joined with
/// ", ", plus " or on the peers" when `peers` is not empty.
std::string DiscoveryPlaces(const std::vector<std::string>& peers);

/// The graph as seen from here: the live entries of DiscoveryRunDirs() followed by those of
/// each peer registry in `peers` (tcp://HOST:PORT, docs/MULTIHOST.md), asked with `timeout`
/// each; unreachable peers are named in `errors`.
std::vector<RegistryEntry> DiscoverGraph(const std::vector<std::string>& peers,
                                         std::chrono::milliseconds timeout,
                                         std::vector<std::string>* errors = nullptr);

}  // namespace p2i::runtime
