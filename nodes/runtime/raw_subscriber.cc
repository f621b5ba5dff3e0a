/// @file raw_subscriber.cc
/// @brief SUB socket with exact topic matching, gap counting and latest-only draining.
#include "nodes/runtime/raw_subscriber.h"

#include <cstring>
#include <stdexcept>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/shutdown.h"
#include "nodes/runtime/wire_io.h"
#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {

RawSubscriber::RawSubscriber(std::string resolved_topic, SubscriberOptions options)
    : topic_(std::move(resolved_topic)),
      topic_frame_(topic_ + std::string(1, '\0')),
      options_(std::move(options)),
      socket_(ZmqContext(), zmq::socket_type::sub) {
  endpoints_ = options_.endpoints;
  if (endpoints_.empty()) endpoints_.push_back(DefaultEndpoint("topic", topic_));
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::maxmsgsize, options_.max_message_bytes);
  socket_.set(zmq::sockopt::rcvhwm,
              options_.latest_only ? options_.latest_only_hwm : options_.rcvhwm);
  if (options_.kernel_buffer_bytes > 0 && !options_.latest_only) {
    socket_.set(zmq::sockopt::rcvbuf, options_.kernel_buffer_bytes);
  }
  socket_.set(zmq::sockopt::subscribe, topic_frame_);
  for (auto& ep : endpoints_) {
    CurveSecurity::Apply(socket_, ep, options_.bind, "subscriber of topic '" + topic_ + "'");
    try {
      if (options_.bind) {
        socket_.bind(ep);
        ep = socket_.get(zmq::sockopt::last_endpoint);
      } else {
        socket_.connect(ep);
      }
    } catch (const zmq::error_t& e) {
      throw std::runtime_error("subscriber of topic '" + topic_ + "': cannot " +
                               (options_.bind ? "bind " : "connect ") + ep + ": " + e.what());
    }
  }
}

RawSubscriber::~RawSubscriber() { socket_.close(); }

void RawSubscriber::Connect(const std::string& endpoint) {
  for (const auto& ep : endpoints_)
    if (ep == endpoint) return;
  CurveSecurity::Apply(socket_, endpoint, false, "subscriber of topic '" + topic_ + "'");
  try {
    socket_.connect(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("subscriber of topic '" + topic_ + "': cannot connect " + endpoint +
                             ": " + e.what());
  }
  endpoints_.push_back(endpoint);
}

bool RawSubscriber::ReadOne(msgs::WireMessage* m, msgs::pb::Header* header, bool* ok) {
  frames_.clear();
  zmq::message_t first;
  if (!socket_.recv(first, zmq::recv_flags::dontwait)) return false;
  frames_.push_back(std::move(first));
  RecvRest(socket_, &frames_);
  *ok = false;
  size_t bytes = 0;
  for (const auto& f : frames_) bytes += f.size();
  stats_.bytes.fetch_add(bytes, std::memory_order_relaxed);

  if (frames_[0].size() != topic_frame_.size() ||
      std::memcmp(frames_[0].data(), topic_frame_.data(), topic_frame_.size()) != 0) {
    last_error_ = "topic frame does not match '" + topic_ + "' exactly";
    stats_.malformed.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  if (!FramesToWire(frames_, 1, m)) {
    last_error_ = "no header frame";
    stats_.malformed.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  std::string error;
  if (!msgs::PeekHeader(m->header, header, &error)) {
    last_error_ = "bad header: " + error;
    stats_.malformed.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  stats_.received.fetch_add(1, std::memory_order_relaxed);
  const uint64_t seq = header->seq();
  auto it = last_seq_.find(header->publisher());
  if (it != last_seq_.end()) {
    if (seq == it->second.first && header->publish_stamp_ns() == it->second.second) {
      stats_.duplicates.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    if (seq > it->second.first + 1) {
      stats_.dropped.fetch_add(seq - it->second.first - 1, std::memory_order_relaxed);
    }
    // seq < last: the publisher restarted; tracking restarts from here.
  }
  last_seq_[header->publisher()] = {seq, header->publish_stamp_ns()};
  *ok = true;
  return true;
}

void RawSubscriber::Deliver(const Handler& handler, msgs::WireMessage&& m,
                            const msgs::pb::Header& h) {
  if (handler(std::move(m), h)) {
    stats_.delivered.fetch_add(1, std::memory_order_relaxed);
  } else {
    stats_.malformed.fetch_add(1, std::memory_order_relaxed);
  }
}

int RawSubscriber::Drain(const Handler& handler) {
  int calls = 0;
  msgs::WireMessage m, newest;
  msgs::pb::Header h, newest_header;
  bool have_newest = false;
  bool ok = false;
  // Bound the loop so a fast publisher cannot starve the executor's other work.
  int read_this_pass = 0;
  for (int i = 0; i < 10000; ++i) {
    if (!ReadOne(&m, &h, &ok)) {
      // Latest-only: a full receive pipe means older messages are still upstream (in the
      // publisher's queue or the kernel buffer); ZeroMQ refills the pipe within microseconds,
      // so wait briefly for them instead of delivering a stale one.
      if (!options_.latest_only || read_this_pass < options_.latest_only_hwm) break;
      zmq::pollitem_t item{socket_.handle(), 0, ZMQ_POLLIN, 0};
      if (Poll(&item, 1, std::chrono::milliseconds(1)) <= 0) break;
      read_this_pass = 0;
      continue;
    }
    ++read_this_pass;
    if (!ok) continue;
    if (options_.latest_only) {
      if (have_newest) stats_.skipped.fetch_add(1, std::memory_order_relaxed);
      newest = std::move(m);
      newest_header = h;
      have_newest = true;
    } else {
      Deliver(handler, std::move(m), h);
      ++calls;
    }
  }
  if (have_newest) {
    Deliver(handler, std::move(newest), newest_header);
    ++calls;
  }
  return calls;
}

bool RawSubscriber::Receive(msgs::WireMessage* out, msgs::pb::Header* header,
                            std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!Shutdown::Requested()) {
    bool got = false;
    if (options_.latest_only) {
      Drain([&](msgs::WireMessage&& m, const msgs::pb::Header& h) {
        *out = std::move(m);
        *header = h;
        got = true;
        return true;
      });
    } else {
      bool ok = false;
      while (!got && ReadOne(out, header, &ok)) got = ok;
      if (got) stats_.delivered.fetch_add(1, std::memory_order_relaxed);
    }
    if (got) return true;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    zmq::pollitem_t items[] = {{socket_.handle(), 0, ZMQ_POLLIN, 0},
                               {nullptr, Shutdown::WakeFd(), ZMQ_POLLIN, 0}};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    Poll(items, 2, std::min(left, std::chrono::milliseconds(100)));
  }
  return false;
}

}  // namespace p2i::runtime
