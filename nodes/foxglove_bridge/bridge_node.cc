/// @file bridge_node.cc
/// @brief Registry discovery -> channels; client subscriptions -> topic subscriptions;
/// messages -> inline-blob protobufs and Foxglove conversions -> WsServer.
#include "nodes/foxglove_bridge/bridge_node.h"

#include <algorithm>
#include <stdexcept>

#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/publisher.h"
#include "recording/foxglove_convert.h"
#include "recording/inline_blobs.h"
#include "recording/proto_schema.h"

namespace p2i::foxglove_bridge {

BridgeNode::BridgeNode(const runtime::NodeArgs& args) : Node("foxglove_bridge", args) {
  options_ = BridgeOptions::FromParameters(Params());
  options_.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  ParametersDone();  // --help and unknown parameters stop here, before the port is bound
  server_ = std::make_unique<WsServer>(options_.Server(), [this](uint32_t channel) {
    GetExecutor().Post([this, channel] { EnsureSubscribed(channel); });
  });
  try {
    server_->Start();
  } catch (const std::runtime_error& e) {
    throw runtime::StartupError(e.what());
  }
  if (!options_.port_file.empty()) {
    const std::string tmp = options_.port_file + ".tmp";
    if (FILE* f = std::fopen(tmp.c_str(), "w")) {
      std::fprintf(f, "%d\n", server_->Port());
      std::fclose(f);
      std::rename(tmp.c_str(), options_.port_file.c_str());
    }
  }
  Log().info("Foxglove WebSocket ({}) on ws://{}:{}", kSubprotocol, options_.server.address,
             server_->Port());
  AddTimer(std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::duration<double>(options_.discovery_period_s)),
           [this] {
             Discover();
             PublishStats();
           });
  GetExecutor().Post([this] { Discover(); });
}

BridgeNode::~BridgeNode() {
  if (server_) server_->Stop();
}

void BridgeNode::OnShutdown() { server_->Stop(); }

void BridgeNode::PublishStats() {
  const auto& s = server_->Stats();
  SetValue("clients", static_cast<double>(s.clients.load()));
  auto set = [this](const std::string& key, uint64_t v, uint64_t* last) {
    if (v > *last) Count(key, v - *last);
    *last = v;
  };
  set("ws_messages_sent", s.messages_sent.load(), &reported_[0]);
  set("ws_bytes_sent", s.bytes_sent.load(), &reported_[1]);
  set("ws_dropped_slow_client", s.dropped.load(), &reported_[2]);
  set("ws_bad_requests", s.bad_requests.load(), &reported_[3]);
  set("ws_unsupported_requests", s.unsupported.load(), &reported_[4]);
}

void BridgeNode::Discover() {
  std::map<std::string, std::string> found;  // topic -> type
  graph_ = runtime::DiscoverGraph(runtime::PeerRegistries(), std::chrono::milliseconds(500));
  for (const auto& e : graph_) {
    if (e.kind != "topic" || runtime::ReachableEndpoints(graph_, "topic", e.name).empty()) continue;
    if (!options_.topics.empty() &&
        std::find(options_.topics.begin(), options_.topics.end(), e.name) == options_.topics.end())
      continue;
    found.emplace(e.name, e.type);
  }
  bool changed = false;
  for (const auto& [topic, type] : found) {
    if (topics_.count(topic)) continue;
    const auto* d = recording::FindDescriptor("p2i.msgs.pb." + type);
    if (!d) continue;
    TopicState t;
    t.type = type;
    t.channel = next_channel_++;
    channels_.push_back({t.channel, topic, "protobuf", d->full_name(), recording::RecordingSchema(d), topic});
    channel_topic_[t.channel] = topic;
    if (options_.foxglove) {
      for (const auto& [suffix, schema] : recording::FoxgloveChannelsFor(type)) {
        const uint32_t id = next_channel_++;
        t.derived[topic + suffix] = id;
        channels_.push_back({id, topic + suffix, "protobuf", schema->full_name(),
                             recording::FileDescriptorSetFor(schema), topic});
        channel_topic_[id] = topic;
      }
    }
    topics_.emplace(topic, std::move(t));
    changed = true;
  }
  // Topics whose publishers are gone: unadvertise (a later publisher gets new channel ids).
  for (auto it = topics_.begin(); it != topics_.end();) {
    if (found.count(it->first)) {
      ++it;
      continue;
    }
    std::set<uint32_t> ids{it->second.channel};
    for (const auto& [name, id] : it->second.derived) ids.insert(id);
    channels_.erase(std::remove_if(channels_.begin(), channels_.end(),
                                   [&](const ChannelInfo& c) { return ids.count(c.id) > 0; }),
                    channels_.end());
    for (uint32_t id : ids) channel_topic_.erase(id);
    it = topics_.erase(it);  // its subscription stays (re-used if the topic comes back)
    changed = true;
  }
  if (changed) server_->SetChannels(channels_);
}

void BridgeNode::EnsureSubscribed(uint32_t channel) {
  const auto c = channel_topic_.find(channel);
  if (c == channel_topic_.end()) return;
  const std::string topic = c->second;
  if (subscribed_.count(topic)) return;  // kept across unadvertise / re-advertise
  const std::vector<std::string> endpoints = runtime::ReachableEndpoints(graph_, "topic", topic);
  runtime::SubscriberOptions o;
  o.endpoints = endpoints;
  subscribed_[topic] = SubscribeRaw(topic,
                       [this, topic](msgs::WireMessage&& m, const msgs::pb::Header&) {
                         OnMessage(topic, std::move(m));
                         return true;
                       },
                       o);
}

void BridgeNode::OnMessage(const std::string& topic, msgs::WireMessage&& m) {
  const auto it = topics_.find(topic);
  if (it == topics_.end()) return;
  const TopicState& t = it->second;
  const uint64_t now = static_cast<uint64_t>(runtime::NowNs());
  if (server_->Wanted(t.channel)) {
    const auto* d = recording::FindDescriptor("p2i.msgs.pb." + t.type);
    std::string error;
    auto rec = d ? recording::InlinedMessage::Make(d, m, &error) : nullptr;
    if (rec) {
      server_->Publish(t.channel, now, std::make_shared<const std::string>(rec->ToString()));
    } else {
      Count("unconvertible_messages");
    }
  }
  bool any_derived = false;
  for (const auto& [name, id] : t.derived) any_derived |= server_->Wanted(id);
  if (!any_derived) return;
  for (auto& f : recording::ToFoxglove(topic, m)) {
    const auto d = t.derived.find(f.topic);
    if (d == t.derived.end() || !server_->Wanted(d->second)) continue;
    server_->Publish(d->second, now, std::make_shared<const std::string>(std::move(f.data)));
  }
}

}  // namespace p2i::foxglove_bridge
