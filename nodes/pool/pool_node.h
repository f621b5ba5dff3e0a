/// @file pool_node.h
/// @brief p2i_pool: one service spread over a pool of worker processes (docs/POOL.md).
#pragma once

#include <memory>
#include <string>

#include "nodes/pool/pool_broker.h"
#include "nodes/runtime/node.h"

namespace p2i::nodes {

/// Parameters: PoolOptions (pool_options.h): service (name served to clients), type (registry
/// type name), backend (endpoint the workers connect to), worker_timeout (s), idle_expiry (s),
/// max_queue. Clients call the service as usual (its
/// default endpoint or the `endpoints` parameter); workers are nodes started with
/// `pool:={render: BACKEND}` (or `{render: ''}` for the default backend).
/// NodeStatus: requests, replies, requeued, workers_lost, refused; values workers, queued.
class PoolNode : public runtime::Node {
 public:
  explicit PoolNode(const runtime::NodeArgs& args);
  ~PoolNode() override;

 private:
  void Publish();
  std::unique_ptr<PoolBroker> broker_;
  std::string registry_path_;
  PoolBrokerStats reported_;
};

}  // namespace p2i::nodes
