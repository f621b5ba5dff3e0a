/// @file raw_publisher.cc
/// @brief PUB socket, topic frame, zero-copy blobs, latching.
#include "nodes/runtime/raw_publisher.h"

#include <stdexcept>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/wire_io.h"
#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {

RawPublisher::RawPublisher(std::string resolved_topic, std::string type_name,
                           std::string node_name, PublisherOptions options)
    : topic_(std::move(resolved_topic)),
      topic_frame_(topic_ + std::string(1, '\0')),
      type_name_(std::move(type_name)),
      options_(std::move(options)),
      socket_(ZmqContext(), zmq::socket_type::pub) {
  endpoint_ = options_.endpoint.empty() ? DefaultEndpoint("topic", topic_) : options_.endpoint;
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::sndhwm, options_.sndhwm);
  if (options_.kernel_buffer_bytes > 0) {
    socket_.set(zmq::sockopt::sndbuf, options_.kernel_buffer_bytes);
  }
  CurveSecurity::Apply(socket_, endpoint_, options_.bind, "publisher of topic '" + topic_ + "'");
  try {
    if (options_.bind) {
      Registry::CheckEndpointFree(endpoint_, "publisher of topic '" + topic_ + "'");
      socket_.bind(endpoint_);
      endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
    } else {
      socket_.connect(endpoint_);
    }
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("publisher of topic '" + topic_ + "': cannot " +
                             (options_.bind ? "bind " : "connect ") + endpoint_ + ": " +
                             e.what() + " (another publisher on this endpoint? set the "
                             "topic's endpoint parameter)");
  }
  if (options_.bind) {
    RegistryEntry entry{"topic", topic_, type_name_, endpoint_, node_name, 0, "", ""};
    // Multi-host launch: a default endpoint is also bound on this host's address.
    if (options_.endpoint.empty())
      entry.remote_endpoint = BindHostEndpoint(socket_, "publisher of topic '" + topic_ + "'");
    registry_path_ = Registry::Register(entry);
  }
}

RawPublisher::~RawPublisher() {
  Registry::Unregister(registry_path_);
  std::lock_guard<std::mutex> lock(mutex_);
  socket_.close();
}

uint64_t RawPublisher::NextSeq() { return ++seq_; }

void RawPublisher::SendLocked(const msgs::WireMessage& m) {
  socket_.send(zmq::buffer(topic_frame_), zmq::send_flags::sndmore);
  SendWire(socket_, m, zmq::send_flags::none);
  stats_.published.fetch_add(1, std::memory_order_relaxed);
  stats_.bytes.fetch_add(msgs::WireSize(m), std::memory_order_relaxed);
}

void RawPublisher::Publish(const msgs::WireMessage& m) {
  std::lock_guard<std::mutex> lock(mutex_);
  SendLocked(m);
  if (options_.latched) {
    last_ = m;  // blobs are shared, so this copies only the header
    has_last_ = true;
  }
}

void RawPublisher::RepublishLatched() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (has_last_) SendLocked(last_);
}

}  // namespace p2i::runtime
