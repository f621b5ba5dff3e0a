/// @file launch_machine.h
/// @brief Which part of a multi-host launch file runs here (`machine` entities, --machine).
#pragma once

#include <string>
#include <vector>

#include "tools/launch_description.h"

namespace p2i::tools {

/// This host's share of a launch file.
struct MachinePlan {
  bool multi_host = false;              ///< the file declares machines
  MachineDescription self;              ///< the machine this launcher plays
  std::vector<NodeDescription> nodes;   ///< its nodes, in file order
  std::vector<MachineDescription> peers;///< every other machine
  /// The peers' registry endpoints, comma-separated (the nodes' $P2I_PEERS).
  std::string PeersText() const;
};

/// Without machines: multi_host false, every node. With machines: the one named `machine`, or
/// when that is empty the single machine whose address is an address of this host (or
/// 127.0.0.1/localhost). Throws LaunchError naming the machines and --machine when none or
/// several match, or when `machine` is not declared.
MachinePlan PlanMachine(const LaunchDescription& description, const std::string& machine,
                        const std::vector<std::string>& local_addresses = {});

/// IPv4/IPv6 addresses of this host's interfaces (getifaddrs), plus "localhost".
std::vector<std::string> LocalAddresses();

}  // namespace p2i::tools
