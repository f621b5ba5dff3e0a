/// @file raw_publisher.h
/// @brief PUB side of a topic at the WireMessage level: [topic '\0'][header][blobs...].
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include <zmq.hpp>

#include "msgs/wire.h"
#include "nodes/runtime/transport_stats.h"

namespace p2i::runtime {

struct PublisherOptions {
  /// "" = DefaultEndpoint("topic", resolved topic) (ipc under $P2I_RUN_DIR). tcp://host:port
  /// and tcp://127.0.0.1:* work too (the bound port is in Endpoint() and the registry).
  std::string endpoint;
  bool bind = true;          ///< false: connect to `endpoint` (a subscriber binds it instead)
  int sndhwm = 1000;         ///< ZeroMQ default; PUB drops (never blocks) beyond it
  /// Kernel send buffer (SO_SNDBUF) in bytes; 0 = OS default. Unix sockets default to ~200 KB,
  /// an eighth of an RGB-D frame; a larger buffer means fewer wake-ups per frame (the kernel
  /// caps it at net.core.wmem_max).
  int kernel_buffer_bytes = 4 << 20;
  bool latched = false;      ///< keep the last message and re-publish it (late joiners)
  double latch_period_s = 1.0;
  /// ZMQ_MAXMSGSIZE of the socket: a publisher receives only subscriptions and the peers'
  /// handshake commands (ZMTP READY, CURVE INITIATE: a few hundred bytes), so a peer sending a
  /// larger frame is disconnected before ZeroMQ allocates it.
  int64_t max_subscription_bytes = 1024;
  /// Refused subscriptions after which the socket is re-bound (every peer is dropped; real
  /// subscribers reconnect within ~100 ms and subscribe again): libzmq keeps every filter it
  /// passes to us in an internal trie until that peer disconnects (~100 bytes per filter
  /// byte), so this bounds it to ~64 KB of filters.
  int64_t max_refused_subscriptions = 64;
};

/// Publishes WireMessages on one topic. The caller fills the header frame (including the u64
/// sequence number: see Publisher<T>, which does it); this class prepends the topic frame, sends
/// the blobs without copying, registers the topic for `p2i topic list` and keeps the last message
/// when latched.
///
/// Subscription floods: the socket is an XPUB in manual mode (ZMQ_XPUB_MANUAL) with
/// ZMQ_MAXMSGSIZE = max_subscription_bytes. Every subscription message is read by this class
/// (before each send) and applied only when its filter is a prefix of the topic frame
/// (`topic\0`, `top`, "" ...); any other filter is refused and counted. A plain PUB keeps every
/// filter a peer sends in its trie (a 1 MB filter costs ~100 MB); here filters are at most
/// max_subscription_bytes long and, past max_refused_subscriptions refused ones, the socket is
/// re-bound, so memory stays bounded however many or long filters peers send.
///
/// Thread-safety: the PUB socket is owned by this object; Publish() and RepublishLatched()
/// serialise on an internal mutex (the mutex is the full memory barrier ZeroMQ requires when a
/// socket is used from more than one thread), so any thread may publish.
class RawPublisher {
 public:
  /// Binds (or connects) at once; throws std::runtime_error naming the topic and endpoint if
  /// that fails (e.g. the ipc endpoint is already bound by another publisher).
  RawPublisher(std::string resolved_topic, std::string type_name, std::string node_name,
               PublisherOptions options);
  ~RawPublisher();
  RawPublisher(const RawPublisher&) = delete;
  RawPublisher& operator=(const RawPublisher&) = delete;

  /// Sends `m` (never blocks: PUB drops when the HWM is full).
  void Publish(const msgs::WireMessage& m);
  /// Next u64 sequence number for this publisher (1, 2, 3, ...). Thread-safe.
  uint64_t NextSeq();
  /// Sends the last published message again if latched (called by the node's latch timer).
  void RepublishLatched();

  const std::string& Topic() const { return topic_; }
  const std::string& TypeName() const { return type_name_; }
  const std::string& Endpoint() const { return endpoint_; }
  const PublisherOptions& Options() const { return options_; }
  const TransportStats& Stats() const { return stats_; }

 private:
  void SendLocked(const msgs::WireMessage& m);
  void ApplySubscriptionsLocked();
  void OpenSocketLocked();  // configures and binds/connects socket_
  int64_t refused_since_open_ = 0;
  std::string host_endpoint_;  // P2I_HOST_ADDRESS endpoint bound beside endpoint_, if any

  std::string topic_;
  std::string topic_frame_;  // topic + '\0'
  std::string type_name_;
  PublisherOptions options_;
  std::string endpoint_;
  std::string registry_path_;
  std::mutex mutex_;
  zmq::socket_t socket_;
  std::atomic<uint64_t> seq_{0};
  bool has_last_ = false;
  msgs::WireMessage last_;
  TransportStats stats_;
};

}  // namespace p2i::runtime
