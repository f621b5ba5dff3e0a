/// @file ws_server.h
/// @brief The WebSocket side of p2i_foxglove_bridge: websocketpp (Boost.Asio) server speaking
/// foxglove.websocket.v1 to many clients, each with a bounded send queue.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "nodes/foxglove_bridge/ws_protocol.h"

namespace p2i::foxglove_bridge {

struct WsServerOptions {
  std::string address = "127.0.0.1";  ///< listen address ("0.0.0.0" = all interfaces)
  int port = 8765;                     ///< 0 = any free port (see Port())
  /// Bytes queued for one client beyond which new messages to it are dropped (counted): a slow
  /// client never blocks the others or grows memory without bound.
  size_t max_queue_bytes = 16u << 20;
  size_t max_client_message_bytes = 1u << 20;  ///< larger client frames close that connection
  std::string name = "p2i_foxglove_bridge";
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

struct WsServerStats {
  std::atomic<uint64_t> clients{0};          ///< connected now
  std::atomic<uint64_t> connections{0};      ///< accepted in total
  std::atomic<uint64_t> rejected{0};         ///< handshakes without the foxglove subprotocol
  std::atomic<uint64_t> messages_sent{0};
  std::atomic<uint64_t> bytes_sent{0};
  std::atomic<uint64_t> dropped{0};          ///< not sent: the client's queue was full
  std::atomic<uint64_t> bad_requests{0};     ///< malformed / unknown-channel / binary requests
  std::atomic<uint64_t> unsupported{0};      ///< well-formed ops this server does not offer
};

/// Thread-safety: Start/Stop from one thread; SetChannels, Publish, Wanted, Port and Stats from
/// any thread (they post to, or read a snapshot of, the server's own I/O thread, which owns
/// every connection and client record).
class WsServer {
 public:
  /// `on_subscribed(channel)` runs on the I/O thread when a channel gets its first subscriber.
  WsServer(WsServerOptions options, std::function<void(uint32_t channel)> on_subscribed);
  ~WsServer();
  WsServer(const WsServer&) = delete;
  WsServer& operator=(const WsServer&) = delete;

  /// Binds and starts the I/O thread. Throws std::runtime_error naming address:port on failure.
  void Start();
  void Stop();
  int Port() const { return port_; }

  /// Replaces the advertised channel set: clients get advertise for new channels, unadvertise
  /// for removed ones (their subscriptions to them end).
  void SetChannels(std::vector<ChannelInfo> channels);
  /// True if some client subscribes to `channel` (skip converting what nobody watches).
  bool Wanted(uint32_t channel) const;
  /// Sends `payload` to every subscription of `channel` (dropping for full client queues).
  void Publish(uint32_t channel, uint64_t timestamp_ns, std::shared_ptr<const std::string> payload);

  const WsServerStats& Stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  WsServerOptions options_;
  std::function<void(uint32_t)> on_subscribed_;
  std::thread thread_;
  std::atomic<int> port_{0};
  std::atomic<size_t> pending_bytes_{0};  // posted to the I/O thread, not yet handled
  mutable std::mutex wanted_mutex_;
  std::map<uint32_t, int> wanted_;  // channel -> number of subscriptions
  WsServerStats stats_;
};

}  // namespace p2i::foxglove_bridge
