/// @file raw_subscriber.h
/// @brief SUB side of a topic at the WireMessage level: exact topic match, per-publisher
/// sequence tracking (drop counting), latest-only draining, malformed frames counted.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <zmq.hpp>

#include "msgs/codec.h"
#include "msgs/wire.h"
#include "nodes/runtime/transport_stats.h"

namespace p2i::runtime {

struct SubscriberOptions {
  /// Endpoints to connect to; empty = DefaultEndpoint("topic", resolved topic).
  std::vector<std::string> endpoints;
  bool bind = false;        ///< bind the (single) endpoint instead (publishers connect)
  /// Deliver only the newest message available at each wake-up; older ones are counted as
  /// `skipped`. Uses a small RCVHWM (ZMQ_CONFLATE cannot be used with multipart messages).
  bool latest_only = false;
  int rcvhwm = 1000;        ///< ZeroMQ default; latest_only forces it to `latest_only_hwm`
  int latest_only_hwm = 2;
  /// Kernel receive buffer (SO_RCVBUF) in bytes; 0 = OS default (see PublisherOptions).
  /// Latest-only subscribers keep the OS default so little stale data waits in the kernel.
  int kernel_buffer_bytes = 4 << 20;
  /// ZMQ_MAXMSGSIZE (per frame): a peer sending a larger frame is disconnected before ZeroMQ
  /// allocates it (as for service servers).
  int64_t max_message_bytes = 64 << 20;
};

/// Receives one topic.
///
/// Subscribes with the prefix "topic\0" and re-checks the whole topic frame on receipt, so
/// "pose" never receives "pose_est". For every well-formed message it peeks the header: per
/// publisher (header.publisher) a sequence number that jumps by more than one adds the gap to
/// `dropped`; an equal one is a latched duplicate (counted, not delivered); a smaller one means
/// the publisher restarted (tracking restarts). A message is malformed (counted, logged by the
/// caller, never delivered, never a crash) if the topic frame differs, the header frame is
/// missing or PeekHeader fails.
///
/// Thread-safety: the SUB socket has one owner thread, the one that calls Drain()/Receive()
/// (normally the node's executor thread). Stats() may be read from any thread.
class RawSubscriber {
 public:
  /// Returns false if the message turned out unusable (e.g. failed to decode): it is then
  /// counted as malformed instead of delivered.
  using Handler = std::function<bool(msgs::WireMessage&& m, const msgs::pb::Header& header)>;

  RawSubscriber(std::string resolved_topic, SubscriberOptions options);
  ~RawSubscriber();
  RawSubscriber(const RawSubscriber&) = delete;
  RawSubscriber& operator=(const RawSubscriber&) = delete;

  /// Non-blocking: handles everything queued now, calling `handler` for each message (or, if
  /// latest_only, only for the newest). Returns the number of calls.
  int Drain(const Handler& handler);
  /// Connects one more endpoint (a publisher found later, e.g. on another host); ignores one
  /// already connected. Owner thread only. Throws std::runtime_error naming topic and endpoint.
  void Connect(const std::string& endpoint);
  /// Blocks up to `timeout` for one message (then behaves like Drain for latest_only).
  /// Returns false on timeout or shutdown.
  bool Receive(msgs::WireMessage* out, msgs::pb::Header* header,
               std::chrono::milliseconds timeout);

  zmq::socket_t& Socket() { return socket_; }
  const std::string& Topic() const { return topic_; }
  const std::vector<std::string>& Endpoints() const { return endpoints_; }
  const TransportStats& Stats() const { return stats_; }
  /// Reason of the last malformed message ("" if none), for logging.
  const std::string& LastError() const { return last_error_; }

 private:
  /// Reads one multipart message without blocking; returns false if none is queued.
  /// `ok` tells whether it was well-formed and new (not a duplicate).
  bool ReadOne(msgs::WireMessage* m, msgs::pb::Header* header, bool* ok);
  void Deliver(const Handler& handler, msgs::WireMessage&& m, const msgs::pb::Header& h);

  std::string topic_;
  std::string topic_frame_;
  SubscriberOptions options_;
  std::vector<std::string> endpoints_;
  zmq::socket_t socket_;
  // per publisher: last seq and its publish stamp (a latched re-send repeats both; a respawned
  // publisher whose first delivered message repeats the old last seq has a newer stamp)
  std::map<std::string, std::pair<uint64_t, int64_t>> last_seq_;
  std::vector<zmq::message_t> frames_;
  std::string last_error_;
  TransportStats stats_;
};

}  // namespace p2i::runtime
