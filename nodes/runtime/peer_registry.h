/// @file peer_registry.h
/// @brief Discovery across hosts (docs/MULTIHOST.md): each host's launcher serves its registry
/// on tcp (RegistryServer); nodes of a multi-host launch also bind their topics and services on
/// the host's address and find remote publishers and servers by asking the peers.
///
/// Environment (set by `p2i launch` for the nodes of a launch file with `machine` entries):
///   P2I_HOST_ADDRESS  this host's address: publishers and servers that use the default ipc
///                     endpoint also bind tcp://ADDRESS:* (recorded as the entry's remote one)
///   P2I_PEERS         comma-separated registry endpoints of the other hosts
///                     (tcp://ADDRESS:PORT); subscribers and service clients without an
///                     explicit endpoint connect to what those registries list
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "nodes/runtime/endpoints.h"

namespace p2i::runtime {

/// $P2I_HOST_ADDRESS ("" when unset).
std::string HostAddress();
/// $P2I_PEERS split at commas (empty when unset).
std::vector<std::string> PeerRegistries();

/// Binds `socket` also on tcp://$P2I_HOST_ADDRESS:* (CURVE applied when configured) and returns
/// that endpoint; "" when no host address is set. Throws std::runtime_error naming `what`.
std::string BindHostEndpoint(zmq::socket_t& socket, const std::string& what);

/// Serves Registry::List() of this process's run dir to other hosts: a ROUTER on `endpoint`
/// answering ["LIST"] with ["OK", one tab-separated entry per line], each entry's endpoint
/// replaced by its remote (tcp) one when it has one. Runs its own thread until destroyed.
class RegistryServer {
 public:
  /// Binds at once; throws std::runtime_error naming the endpoint on failure.
  explicit RegistryServer(const std::string& endpoint);
  ~RegistryServer();
  RegistryServer(const RegistryServer&) = delete;
  RegistryServer& operator=(const RegistryServer&) = delete;
  const std::string& Endpoint() const { return endpoint_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string endpoint_;
};

/// Asks one peer registry. Returns false with `error` when no reply came within `timeout`.
bool QueryPeer(const std::string& registry_endpoint, std::chrono::milliseconds timeout,
               std::vector<RegistryEntry>* entries, std::string* error);

/// Local entries (of `local_run_dirs`) followed by every peer's; unreachable peers are named
/// in `errors`.
std::vector<RegistryEntry> ListGraph(const std::vector<std::string>& local_run_dirs,
                                     const std::vector<std::string>& peers,
                                     std::chrono::milliseconds timeout,
                                     std::vector<std::string>* errors = nullptr);

/// Endpoints a process here can connect to for (kind, name): local entries' endpoints and
/// remote entries' tcp endpoints (remote ipc paths are unreachable and skipped).
std::vector<std::string> ReachableEndpoints(const std::vector<RegistryEntry>& entries,
                                            const std::string& kind, const std::string& name);

/// Endpoint of service `name`: a live local server's, else the first peer's tcp one, else ""
/// (asks the peers with `timeout` each). Used by service clients on every (re)connect.
std::string FindServiceEndpoint(const std::string& name, const std::vector<std::string>& peers,
                                std::chrono::milliseconds timeout);

/// A thread that asks the peers every `period` for watched names and calls each watcher (on
/// the watcher thread) with endpoints it has not reported before. Stops in its destructor.
class PeerWatcher {
 public:
  using Callback = std::function<void(const std::vector<std::string>& new_endpoints)>;
  PeerWatcher(std::vector<std::string> peers, std::chrono::milliseconds period);
  ~PeerWatcher();
  /// Thread-safe.
  void Watch(const std::string& kind, const std::string& name, Callback cb);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace p2i::runtime
