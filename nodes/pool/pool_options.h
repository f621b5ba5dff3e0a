/// @file pool_options.h
/// @brief Every parameter of the pool node in one Options struct: defaults in the field
/// initialisers (written once), read from the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/runtime/parameters.h"

namespace p2i::nodes {

/// The pool node's configuration (docs/POOL.md). A value type: thread-compatible.
struct PoolOptions {
  std::string service = "render";        ///< service name served to clients
  std::string type = "RenderRequest";    ///< request type name (for p2i topic list -v)
  std::string backend;                   ///< workers' endpoint; "" = ipc://$P2I_RUN_DIR/pool.<service>.ipc
  double worker_timeout = 3.0;  ///< s a worker may take for one request before presumed dead
  double idle_expiry = 3.5;     ///< s an idle worker may go without a heartbeat
  int max_queue = 10000;        ///< requests waiting for a worker, at most

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description) and returns the values supplied or the defaults. Throws runtime::StartupError
  /// for a value of the wrong type.
  static PoolOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it.
  void Validate() const;
};

}  // namespace p2i::nodes
