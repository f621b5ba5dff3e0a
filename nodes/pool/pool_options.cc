/// @file pool_options.cc
/// @brief The pool node's parameters -> PoolOptions, and their validation.
#include "nodes/pool/pool_options.h"

#include "nodes/runtime/option_error.h"

namespace p2i::nodes {

PoolOptions PoolOptions::FromParameters(runtime::Parameters& p) {
  PoolOptions o;  // the defaults, written once in the field initialisers
  o.service = p.Declare<std::string>("service", o.service, "service name to serve");
  o.type = p.Declare<std::string>("type", o.type, "request type name (for p2i topic list -v)");
  o.backend = p.Declare<std::string>(
      "backend", o.backend,
      "endpoint the workers connect to; '' = ipc://$P2I_RUN_DIR/pool.<service>.ipc");
  o.worker_timeout = p.Declare<double>(
      "worker_timeout", o.worker_timeout,
      "s a worker may take for one request before it is presumed dead");
  o.idle_expiry = p.Declare<double>("idle_expiry", o.idle_expiry,
                                    "s an idle worker may go without a heartbeat");
  o.max_queue =
      p.Declare<int>("max_queue", o.max_queue, "requests waiting for a worker, at most");
  return o;
}

void PoolOptions::Validate() const {
  using runtime::CheckOption;
  CheckOption(!service.empty(), "pool", "service", service, "name a service",
              "e.g. service:=render");
  CheckOption(worker_timeout > 0.0, "pool", "worker_timeout", worker_timeout,
              "be > 0", "seconds, e.g. worker_timeout:=3");
  CheckOption(idle_expiry > 0.0, "pool", "idle_expiry", idle_expiry, "be > 0",
              "seconds, e.g. idle_expiry:=3.5");
  CheckOption(max_queue > 0, "pool", "max_queue", max_queue, "be > 0", "e.g. max_queue:=10000");
}

}  // namespace p2i::nodes
