/// @file bridge_options.cc
/// @brief The bridge node's parameters -> BridgeOptions, and their validation.
#include "nodes/foxglove_bridge/bridge_options.h"

#include "nodes/runtime/option_error.h"

namespace p2i::foxglove_bridge {
namespace {

constexpr double kMiB = 1 << 20;

}  // namespace

BridgeOptions BridgeOptions::FromParameters(runtime::Parameters& p) {
  BridgeOptions o;  // the defaults, written once in the field initialisers
  o.server.address = p.Declare<std::string>("address", o.server.address,
                                            "listen address (0.0.0.0 = all interfaces)");
  o.server.port = p.Declare<int>("port", o.server.port, "WebSocket port (0 = any free port)");
  o.max_queue_mb = p.Declare<double>("max_queue_mb", o.max_queue_mb,
                                     "per-client send queue (MiB); beyond it drop");
  o.foxglove = p.Declare<bool>("foxglove", o.foxglove,
                               "also advertise Foxglove-schema channels (images, tf, poses)");
  o.discovery_period_s = p.Declare<double>("discovery_period", o.discovery_period_s,
                                           "s between registry scans for topics");
  o.topics = p.Declare<std::vector<std::string>>("topics", o.topics,
                                                 "only these topics (empty = all)");
  o.port_file = p.Declare<std::string>("port_file", o.port_file,
                                       "write the bound port here (tests, port:=0)");
  return o;
}

void BridgeOptions::Validate() const {
  using runtime::CheckOption;
  CheckOption(!server.address.empty(), "foxglove_bridge", "address", server.address,
              "name a listen address", "e.g. address:=127.0.0.1 (0.0.0.0 = all interfaces)");
  CheckOption(server.port >= 0 && server.port <= 65535, "foxglove_bridge", "port", server.port,
              "be in [0, 65535]", "port:=0 takes any free port");
  CheckOption(max_queue_mb * kMiB >= 1024, "foxglove_bridge", "max_queue_mb", max_queue_mb,
              "be at least 1 KiB (0.0009765625)", "e.g. max_queue_mb:=16");
  CheckOption(discovery_period_s > 0.0, "foxglove_bridge", "discovery_period",
              discovery_period_s, "be > 0", "seconds, e.g. discovery_period:=0.5");
  Server().Validate();  // the server's own limits (max_client_message_bytes)
}

WsServerOptions BridgeOptions::Server() const {
  WsServerOptions s = server;
  s.max_queue_bytes = static_cast<size_t>(max_queue_mb * kMiB);
  return s;
}

}  // namespace p2i::foxglove_bridge
