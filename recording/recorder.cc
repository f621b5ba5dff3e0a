/// @file recorder.cc
/// @brief Topic subscriptions (explicit or discovered) -> MCAP channels and messages.
#include "recording/recorder.h"

#include <algorithm>
#include <filesystem>
#include <thread>
#include <stdexcept>

#include <zmq.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/graph_discovery.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/wire_io.h"
#include "recording/foxglove_convert.h"
#include "recording/inline_blobs.h"
#include "recording/proto_schema.h"

namespace p2i::recording {

void RecorderOptions::Validate() const {
  if (output.empty()) throw std::invalid_argument("record: -o FILE.mcap is required");
  if (topics.empty() && !all)
    throw std::invalid_argument("record: name topics to record, or -a for all of them");
  if (!topics.empty() && all)
    throw std::invalid_argument("record: give topics or -a, not both");
  for (const auto& t : topics) {
    if (t.empty() || t[0] != '/')
      throw std::invalid_argument("record: topic '" + t + "' must be absolute (start with /)");
  }
  if (!(discovery_period_s > 0))
    throw std::invalid_argument("record: discovery_period_s must be > 0");
  if (queue_messages < 1) throw std::invalid_argument("record: queue_messages must be >= 1");
  mcap.Validate();
}

Recorder::Recorder(RecorderOptions options) : options_(std::move(options)) {
  options_.Validate();
}

Recorder::~Recorder() {
  try {
    Stop();
  } catch (...) {
  }
}

void Recorder::Start() {
  if (!options_.overwrite && std::filesystem::exists(options_.output)) {
    throw std::runtime_error("record: " + options_.output +
                             " exists (choose another -o, or pass --overwrite)");
  }
  McapWriterOptions o = options_.mcap;
  o.library = "p2i record";
  writer_.Open(options_.output, o);
  for (const auto& t : options_.topics) Subscribe(t, {});
  next_discovery_ = std::chrono::steady_clock::now();
  Discover();
}

void Recorder::Stop() {
  if (writer_.IsOpen()) writer_.Close();
}

void Recorder::Subscribe(const std::string& topic, const std::vector<std::string>& endpoints) {
  auto& t = topics_[topic];
  if (t.sub) return;
  runtime::SubscriberOptions so;
  so.endpoints = endpoints.empty()
                     ? std::vector<std::string>{runtime::DefaultEndpoint("topic", topic)}
                     : endpoints;
  so.rcvhwm = options_.queue_messages;
  t.sub = std::make_unique<runtime::RawSubscriber>(topic, so);
  t.endpoints.insert(so.endpoints.begin(), so.endpoints.end());
  stats_[topic];
}

void Recorder::Discover() {
  const auto now = std::chrono::steady_clock::now();
  if (now < next_discovery_) return;
  next_discovery_ = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(options_.discovery_period_s));
  // The graph as `p2i topic list` sees it: $P2I_RUN_DIR, else every running launch of this
  // user, plus the peers of $P2I_PEERS.
  const auto graph = runtime::DiscoverGraph(runtime::PeerRegistries(), std::chrono::milliseconds(500));
  std::map<std::string, std::vector<std::string>> found;
  for (const auto& e : graph) {
    if (e.kind != "topic" || found.count(e.name)) continue;
    auto endpoints = runtime::ReachableEndpoints(graph, "topic", e.name);
    if (!endpoints.empty()) found[e.name] = std::move(endpoints);
  }
  for (const auto& [name, endpoints] : found) {
    auto it = topics_.find(name);
    if (it == topics_.end() || !it->second.sub) {
      if (options_.all) Subscribe(name, endpoints);
      continue;
    }
    for (const auto& ep : endpoints) {  // a publisher on a new endpoint (tcp, respawned)
      if (it->second.endpoints.insert(ep).second) it->second.sub->Socket().connect(ep);
    }
  }
}

uint16_t Recorder::ChannelFor(const std::string& topic, const google::protobuf::Descriptor* d,
                              const std::map<std::string, std::string>& metadata) {
  auto s = schema_ids_.find(d->full_name());
  if (s == schema_ids_.end()) {
    s = schema_ids_.emplace(d->full_name(),
                            writer_.AddSchema(d->full_name(), "protobuf", RecordingSchema(d)))
            .first;
  }
  return writer_.AddChannel(s->second, topic, "protobuf", metadata);
}

void Recorder::Write(const std::string& topic, Topic* t, const msgs::WireMessage& m,
                     const msgs::pb::Header& h, uint64_t log_time) {
  auto& st = stats_[topic];
  const google::protobuf::Descriptor* d = DescriptorOf(h.type());
  std::string error;
  std::unique_ptr<InlinedMessage> msg = d ? InlinedMessage::Make(d, m, &error) : nullptr;
  if (!msg) {
    ++t->unwritable;
    last_error_ = topic + ": " + (d ? error : "unknown message type " + std::to_string(h.type()));
    return;
  }
  if (t->channel == 0) {
    t->channel = ChannelFor(topic, d, {{"p2i_type", msgs::TypeName(h.type())}});
    st.type = d->full_name();
  }
  const size_t size = msg->Size();
  const uint64_t publish = h.publish_stamp_ns() > 0 ? h.publish_stamp_ns() : log_time;
  writer_.Write(t->channel, ++t->sequence, log_time, publish, size, [&](uint8_t* dst) {
    msg->WriteTo(dst);
  });
  ++st.messages;
  st.bytes += size;
  if (!options_.foxglove) return;
  for (auto& f : ToFoxglove(topic, m)) {
    auto c = extra_channels_.find(f.topic);
    if (c == extra_channels_.end())
      c = extra_channels_.emplace(f.topic, ChannelFor(f.topic, f.schema, {{"source", topic}})).first;
    writer_.Write(c->second, ++extra_sequence_[f.topic], log_time, publish, f.data.data(),
                  f.data.size());
  }
}

int Recorder::SpinOnce(std::chrono::milliseconds max_wait) {
  Discover();
  std::vector<zmq::pollitem_t> items;
  std::vector<std::pair<const std::string*, Topic*>> order;
  for (auto& [name, t] : topics_) {
    if (!t.sub) continue;
    items.push_back({t.sub->Socket().handle(), 0, ZMQ_POLLIN, 0});
    order.emplace_back(&name, &t);
  }
  int written = 0;
  if (items.empty()) {
    std::this_thread::sleep_for(max_wait);
  } else if (runtime::Poll(items.data(), items.size(), max_wait) > 0) {
    for (size_t i = 0; i < items.size(); ++i) {
      if (!(items[i].revents & ZMQ_POLLIN)) continue;
      const std::string& name = *order[i].first;
      Topic* t = order[i].second;
      t->sub->Drain([&](msgs::WireMessage&& m, const msgs::pb::Header& h) {
        Write(name, t, m, h, static_cast<uint64_t>(runtime::NowNs()));
        ++written;
        return true;
      });
    }
  }
  for (auto& [name, t] : topics_) {
    if (!t.sub) continue;
    auto& st = stats_[name];
    st.dropped = t.sub->Stats().dropped.load();
    st.malformed = t.unwritable + t.sub->Stats().malformed.load();
  }
  writer_.FlushIfDue();
  return written;
}

}  // namespace p2i::recording
