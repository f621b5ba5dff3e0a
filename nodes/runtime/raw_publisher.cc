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
      socket_(ZmqContext(), zmq::socket_type::xpub) {
  endpoint_ = options_.endpoint.empty() ? DefaultEndpoint("topic", topic_) : options_.endpoint;
  if (options_.bind) Registry::CheckEndpointFree(endpoint_, "publisher of topic '" + topic_ + "'");
  OpenSocketLocked();
  if (options_.bind) {
    RegistryEntry entry{"topic", topic_, type_name_, endpoint_, node_name, 0, "", ""};
    entry.remote_endpoint = host_endpoint_;
    registry_path_ = Registry::Register(entry);
  }
}

void RawPublisher::OpenSocketLocked() {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::xpub_manual, true);
  socket_.set(zmq::sockopt::maxmsgsize, options_.max_subscription_bytes);
  socket_.set(zmq::sockopt::sndhwm, options_.sndhwm);
  if (options_.kernel_buffer_bytes > 0) {
    socket_.set(zmq::sockopt::sndbuf, options_.kernel_buffer_bytes);
  }
  CurveSecurity::Apply(socket_, endpoint_, options_.bind, "publisher of topic '" + topic_ + "'");
  try {
    if (options_.bind) {
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
  if (options_.bind && options_.endpoint.empty()) {
    // Multi-host launch: a default endpoint is also bound on this host's address (the same
    // port again when the socket is opened again after a flood).
    const std::string what = "publisher of topic '" + topic_ + "'";
    if (host_endpoint_.empty()) {
      host_endpoint_ = BindHostEndpoint(socket_, what);
    } else {
      CurveSecurity::Apply(socket_, host_endpoint_, true, what);
      socket_.bind(host_endpoint_);
    }
  }
  refused_since_open_ = 0;
}

RawPublisher::~RawPublisher() {
  Registry::Unregister(registry_path_);
  std::lock_guard<std::mutex> lock(mutex_);
  socket_.close();
}

uint64_t RawPublisher::NextSeq() { return ++seq_; }

void RawPublisher::ApplySubscriptionsLocked() {
  // Bounded per call so a flood cannot stall publishing; the rest waits in the socket's queue
  // (at most rcvhwm messages of at most max_subscription_bytes).
  for (int i = 0; i < 1000; ++i) {
    zmq::message_t msg;
    if (!socket_.recv(msg, zmq::recv_flags::dontwait)) return;
    const auto* data = static_cast<const char*>(msg.data());
    const bool is_sub = msg.size() >= 1 && (data[0] == 0 || data[0] == 1);
    const std::string filter = is_sub ? std::string(data + 1, msg.size() - 1) : std::string();
    if (!is_sub || filter.size() > topic_frame_.size() ||
        topic_frame_.compare(0, filter.size(), filter) != 0) {
      stats_.refused_subscriptions.fetch_add(1, std::memory_order_relaxed);
      if (++refused_since_open_ > options_.max_refused_subscriptions) {
        // Drop every peer (and libzmq's copy of their filters): bind the same endpoint again.
        socket_.close();
        socket_ = zmq::socket_t(ZmqContext(), zmq::socket_type::xpub);
        try {
          OpenSocketLocked();
        } catch (const std::exception&) {
          // Not bound again: publishing goes nowhere rather than crashing; the counters show it.
        }
        return;
      }
      continue;
    }
    // In manual mode this applies to the pipe the message came from.
    if (data[0] == 1) {
      socket_.set(zmq::sockopt::subscribe, filter);
    } else {
      socket_.set(zmq::sockopt::unsubscribe, filter);
    }
  }
}

void RawPublisher::SendLocked(const msgs::WireMessage& m) {
  ApplySubscriptionsLocked();
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
