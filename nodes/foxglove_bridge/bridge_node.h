/// @file bridge_node.h
/// @brief p2i_foxglove_bridge: advertises every p2i topic (from the discovery registry) as a
/// Foxglove WebSocket channel with its protobuf schema, plus Foxglove-schema channels
/// (RawImage, CameraCalibration, FrameTransform, PoseInFrame) derived from frames, views and
/// poses; subscribes to a topic only while some client watches it.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "nodes/foxglove_bridge/bridge_options.h"
#include "nodes/foxglove_bridge/ws_server.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/node.h"

namespace p2i::foxglove_bridge {

/// Parameters: BridgeOptions (bridge_options.h). Threads: the node's executor (discovery timer, subscriptions, conversion) and the
/// WsServer's I/O thread; they meet only through WsServer's thread-safe calls and Post().
class BridgeNode : public runtime::Node {
 public:
  explicit BridgeNode(const runtime::NodeArgs& args);
  ~BridgeNode() override;
  int Port() const { return server_->Port(); }
  const WsServerStats& ServerStats() const { return server_->Stats(); }

 protected:
  void OnShutdown() override;

 private:
  struct TopicState {
    std::string type;                        ///< p2i type name ("RgbdFrame")
    uint32_t channel = 0;                    ///< the p2i channel
    std::map<std::string, uint32_t> derived; ///< foxglove topic -> channel
  };
  void Discover();
  void EnsureSubscribed(uint32_t channel);
  void OnMessage(const std::string& topic, msgs::WireMessage&& m);
  void PublishStats();

  BridgeOptions options_;
  std::unique_ptr<WsServer> server_;
  std::map<std::string, TopicState> topics_;      // executor thread only
  std::vector<runtime::RegistryEntry> graph_;     // last discovery (executor only)
  std::map<uint32_t, std::string> channel_topic_; // channel -> source topic (executor only)
  /// Topic subscriptions made for clients (executor only). The node owns them until it closes.
  std::map<std::string, std::shared_ptr<runtime::RawSubscriber>> subscribed_;
  std::vector<ChannelInfo> channels_;
  uint32_t next_channel_ = 1;
  uint64_t reported_[5] = {};  // WsServerStats already copied into the node's counters
};

}  // namespace p2i::foxglove_bridge
