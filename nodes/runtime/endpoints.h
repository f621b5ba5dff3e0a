/// @file endpoints.h
/// @brief Where default ipc:// endpoints live ($P2I_RUN_DIR) and the discovery registry that
/// `p2i topic list` reads.
#pragma once

#include <string>
#include <vector>

namespace p2i::runtime {

/// $P2I_RUN_DIR, else /tmp/p2i-$UID; created (mode 0700) on first use.
std::string RunDir();

/// Default endpoint for a resolved name: ipc://$P2I_RUN_DIR/<kind>.<name with '/' -> '.'>.ipc
/// (kind = "topic" or "service"). Over-long paths (ipc paths are limited to ~107 bytes) fall
/// back to a hashed file name. Every process of a launch derives the same endpoint.
std::string DefaultEndpoint(const std::string& kind, const std::string& resolved_name);

/// One entry of the discovery registry: a file $P2I_RUN_DIR/registry/<pid>.<kind>.<name>
/// written by the process that binds the endpoint, removed when it closes (stale entries of
/// dead processes are ignored and cleaned by List()).
struct RegistryEntry {
  std::string kind;      ///< "topic" or "service"
  std::string name;      ///< resolved name
  std::string type;      ///< message type name, e.g. "RgbdFrame"
  std::string endpoint;  ///< bound endpoint (the actual one, also for tcp://*:0)
  std::string node;      ///< full node name
  int pid = 0;
  /// Multi-host graphs: the tcp endpoint the same socket also bound on $P2I_HOST_ADDRESS for
  /// other hosts ("" when none; see peer_registry.h).
  std::string remote_endpoint;
  /// Where the entry was found: "" = this host's run dir, else the peer registry endpoint.
  std::string host;
};

/// Process-level registry helpers. Thread-safe (file operations only).
class Registry {
 public:
  /// Writes the entry file; returns its path ("" if the run dir is not writable: discovery is
  /// best-effort and never fails a node).
  static std::string Register(const RegistryEntry& e);
  static void Unregister(const std::string& path);
  /// Throws std::runtime_error if a live process has registered `endpoint` already (ZeroMQ
  /// would silently take an ipc:// path over from its current owner). `what` names the caller
  /// in the message.
  static void CheckEndpointFree(const std::string& endpoint, const std::string& what);
  /// All live entries (pid still running), sorted by kind and name.
  static std::vector<RegistryEntry> List();
  /// The same for the registry of another run dir.
  static std::vector<RegistryEntry> ListDir(const std::string& run_dir);
  /// Run dirs of this user's running launches: /tmp/p2i-$UID and each /tmp/p2i-$UID/launch-*
  /// with a registry (what `p2i topic` reads when $P2I_RUN_DIR is not set).
  static std::vector<std::string> UserRunDirs();
};

}  // namespace p2i::runtime
