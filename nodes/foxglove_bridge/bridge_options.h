/// @file bridge_options.h
/// @brief Every parameter of the Foxglove bridge node in one Options struct: defaults in the
/// field initialisers (written once), read from the node's parameters in one function, one
/// Validate().
#pragma once

#include <string>
#include <vector>

#include "nodes/foxglove_bridge/ws_server.h"
#include "nodes/runtime/parameters.h"

namespace p2i::foxglove_bridge {

/// The bridge node's configuration (docs/FOXGLOVE.md). A value type: thread-compatible.
struct BridgeOptions {
  WsServerOptions server;  ///< address, port (max_queue_bytes: see Server())
  /// Per-client send queue in MiB; the server's default (16 MiB) unless set.
  double max_queue_mb = static_cast<double>(WsServerOptions().max_queue_bytes) / (1 << 20);
  bool foxglove = true;             ///< also advertise the Foxglove-schema channels
  double discovery_period_s = 0.5;  ///< registry re-read period (new / gone topics)
  std::vector<std::string> topics;  ///< only these topics (empty = all)
  std::string port_file;            ///< write the bound port here (tests, port:=0); "" = no

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static BridgeOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it.
  void Validate() const;

  /// `server` with max_queue_bytes = max_queue_mb MiB (Validate() first).
  WsServerOptions Server() const;
};

}  // namespace p2i::foxglove_bridge
