/// @file pool_node.cc
/// @brief p2i_pool: parameters, sockets on the executor, registry entry, status counters.
#include "nodes/pool/pool_node.h"

#include "nodes/pool/pool_options.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/peer_registry.h"

namespace p2i::nodes {

PoolNode::PoolNode(const runtime::NodeArgs& args) : Node("pool", args) {
  const PoolOptions options = PoolOptions::FromParameters(Params());
  options.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  const std::string& service = options.service;
  ParametersDone();  // --help and unknown parameters stop here, before anything is bound
  const std::string resolved = Resolve(service);
  PoolBrokerOptions o;
  const std::string given_endpoint = EndpointFor(service, resolved);  // `endpoints` entry
  o.frontend = given_endpoint.empty() ? runtime::DefaultEndpoint("service", resolved) : given_endpoint;
  o.backend =
      options.backend.empty() ? runtime::DefaultEndpoint("pool", resolved) : options.backend;
  o.worker_timeout = std::chrono::milliseconds(static_cast<int64_t>(options.worker_timeout * 1000));
  o.idle_expiry = std::chrono::milliseconds(static_cast<int64_t>(options.idle_expiry * 1000));
  o.max_queue = static_cast<size_t>(options.max_queue);
  runtime::Registry::CheckEndpointFree(o.frontend, "pool of service '" + resolved + "'");
  broker_ = std::make_unique<PoolBroker>(o, [this](const std::string& text) {
    WarnThrottled("pool", text);
  });
  runtime::RegistryEntry entry{"service", resolved, options.type, broker_->FrontendEndpoint(),
                               FullName(), 0, "", ""};
  if (given_endpoint.empty())  // multi-host launch: reachable from the other hosts too
    entry.remote_endpoint = runtime::BindHostEndpoint(broker_->Frontend(), "pool frontend");
  registry_path_ = runtime::Registry::Register(entry);
  GetExecutor().AddSocket(&broker_->Frontend(), [this] { broker_->OnFrontend(); });
  GetExecutor().AddSocket(&broker_->Backend(), [this] { broker_->OnBackend(); });
  AddTimer(std::chrono::milliseconds(100), [this] {
    broker_->OnTimer();
    Publish();
  });
  Log().info("pool of {}: clients at {}, workers connect to {}", resolved,
             broker_->FrontendEndpoint(), broker_->BackendEndpoint());
}

PoolNode::~PoolNode() {
  runtime::Registry::Unregister(registry_path_);
  if (broker_) {
    GetExecutor().RemoveSocket(&broker_->Frontend());
    GetExecutor().RemoveSocket(&broker_->Backend());
  }
}

void PoolNode::Publish() {
  const PoolBrokerStats& s = broker_->Stats();
  Count("pool_requests", s.requests - reported_.requests);
  Count("pool_replies", s.replies - reported_.replies);
  Count("pool_requeued", s.requeued - reported_.requeued);
  Count("pool_workers_lost", s.workers_lost - reported_.workers_lost);
  Count("pool_refused", s.refused - reported_.refused);
  SetValue("pool_workers", static_cast<double>(s.workers));
  SetValue("pool_queued", static_cast<double>(s.queued));
  reported_ = s;
}

}  // namespace p2i::nodes
