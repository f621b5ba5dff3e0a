/// @file launch_machine.cc
/// @brief Choosing this host's machine of a launch file and its nodes.
#include "tools/launch_machine.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>

#include <algorithm>

#include "tools/launch_error.h"

namespace p2i::tools {

std::string MachinePlan::PeersText() const {
  std::string out;
  for (const auto& p : peers) out += (out.empty() ? "" : ",") + p.RegistryEndpoint();
  return out;
}

std::vector<std::string> LocalAddresses() {
  std::vector<std::string> out = {"localhost"};
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return out;
  for (ifaddrs* a = list; a; a = a->ifa_next) {
    if (!a->ifa_addr) continue;
    char buf[INET6_ADDRSTRLEN] = {0};
    if (a->ifa_addr->sa_family == AF_INET) {
      inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr, buf, sizeof(buf));
    } else if (a->ifa_addr->sa_family == AF_INET6) {
      inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(a->ifa_addr)->sin6_addr, buf,
                sizeof(buf));
    } else {
      continue;
    }
    out.push_back(buf);
  }
  freeifaddrs(list);
  return out;
}

MachinePlan PlanMachine(const LaunchDescription& d, const std::string& machine,
                        const std::vector<std::string>& local_addresses) {
  MachinePlan plan;
  if (d.machines.empty()) {
    if (!machine.empty())
      throw LaunchError("--machine " + machine + ": the launch file declares no machines");
    plan.nodes = d.nodes;
    return plan;
  }
  plan.multi_host = true;
  std::string names;
  for (const auto& m : d.machines) names += (names.empty() ? "" : ", ") + m.name + " (" + m.address + ")";
  const MachineDescription* self = nullptr;
  if (!machine.empty()) {
    for (const auto& m : d.machines)
      if (m.name == machine) self = &m;
    if (!self)
      throw LaunchError("--machine " + machine + " is not declared (machines: " + names + ")");
  } else {
    const auto local = local_addresses.empty() ? LocalAddresses() : local_addresses;
    std::vector<const MachineDescription*> matches;
    for (const auto& m : d.machines)
      if (std::find(local.begin(), local.end(), m.address) != local.end()) matches.push_back(&m);
    if (matches.size() != 1)
      throw LaunchError(std::string(matches.empty() ? "none" : "several") +
                        " of the launch file's machines have an address of this host (machines: " +
                        names + "); choose one with --machine NAME");
    self = matches.front();
  }
  plan.self = *self;
  for (const auto& m : d.machines)
    if (m.name != self->name) plan.peers.push_back(m);
  for (const auto& n : d.nodes)
    if (n.machine == self->name) plan.nodes.push_back(n);
  return plan;
}

}  // namespace p2i::tools
