/// @file raw_service.h
/// @brief Services at the WireMessage level: ROUTER server, DEALER client ("Lazy Pirate").
///
/// Frames (the client's DEALER adds no identity; the ROUTER prepends/strips the peer's):
///   request : [""][request id: u64 little-endian][header][blobs...]
///   reply   : [""][request id][status][header][blobs...]   status "" = ok, else error text
///             (then there is no header)
/// The typed layer also writes the request id into header.request_id of both messages.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <vector>
#include <functional>
#include <string>

#include <zmq.hpp>

#include "msgs/wire.h"

namespace p2i::runtime {

struct ServiceStats {
  std::atomic<uint64_t> requests{0};      ///< server: requests handled; client: calls made
  std::atomic<uint64_t> errors{0};        ///< server: handler errors; client: failed calls
  std::atomic<uint64_t> malformed{0};     ///< bad envelopes / replies
  std::atomic<uint64_t> timeouts{0};      ///< client: attempts that timed out
  std::atomic<uint64_t> reconnects{0};    ///< client: sockets closed and reopened
  std::atomic<uint64_t> stale_replies{0}; ///< client: replies to an older request id
};

struct ServiceServerOptions {
  std::string endpoint;  ///< "" = DefaultEndpoint("service", name)
  /// ZMQ_MAXMSGSIZE on the bound ROUTER: a peer that sends a larger frame is disconnected
  /// (ZeroMQ enforces it per frame; the largest frame of a request is its biggest blob).
  int64_t max_message_bytes = 64ll << 20;
  /// Pool worker: instead of binding, connect a DEALER to this broker backend endpoint
  /// (nodes/pool, docs/POOL.md), announce "READY" and serve what the broker forwards; the
  /// frames are the same as on the bound ROUTER. "" = an ordinary server.
  std::string worker_of;
};

/// Serves one service. Requests are handled one at a time, in arrival order, on the owner
/// thread, from any number of clients (the ROUTER routes each reply back to its client).
///
/// Thread-safety: the ROUTER socket is owned by the thread that calls Drain() (normally the
/// node's executor thread).
class RawServiceServer {
 public:
  /// Returns true and fills `reply`, or false and sets `error` (sent back to the client).
  using Handler = std::function<bool(const msgs::WireMessage& request, uint64_t request_id,
                                     msgs::WireMessage* reply, std::string* error)>;

  /// Binds at once; throws std::runtime_error naming service and endpoint on failure.
  RawServiceServer(std::string resolved_name, std::string type_name, std::string node_name,
                   ServiceServerOptions options, Handler handler);
  ~RawServiceServer();

  /// Handles every queued request (non-blocking). Returns how many.
  int Drain();
  /// Pool worker: tells the broker this worker is alive and idle (a ["READY"] frame); the node
  /// calls it every second. No-op for an ordinary server.
  void Heartbeat();

  zmq::socket_t& Socket() { return socket_; }
  const std::string& Name() const { return name_; }
  const std::string& Endpoint() const { return endpoint_; }
  const ServiceStats& Stats() const { return stats_; }
  const std::string& LastError() const { return last_error_; }

 private:
  std::string name_;
  ServiceServerOptions options_;
  Handler handler_;
  std::string endpoint_;
  std::string registry_path_;
  zmq::socket_t socket_;
  std::vector<zmq::message_t> frames_;
  std::string last_error_;
  ServiceStats stats_;
};

struct ServiceClientOptions {
  std::string endpoint;  ///< "" = DefaultEndpoint("service", name)
  std::chrono::milliseconds timeout{1000};  ///< per attempt
  int retries = 2;       ///< attempts after the first; total = 1 + retries
  /// Called before each (re)connect; a non-empty result replaces the endpoint (multi-host
  /// discovery, peer_registry.h). Empty function = keep `endpoint`.
  std::function<std::string()> resolver;
};

/// Calls one service with Lazy Pirate reliability: send, wait up to `timeout`; on timeout close
/// the socket (linger 0), open a fresh one and resend, up to `retries` times, then report
/// failure. Replies are matched by request id; stale ones are counted and dropped. A lost reply
/// can therefore never wedge the client (as it would with REQ).
///
/// Thread-safety: the DEALER socket is owned by the thread that calls Call(); use one client per
/// thread for concurrent calls. Stats() may be read from any thread.
class RawServiceClient {
 public:
  RawServiceClient(std::string resolved_name, ServiceClientOptions options);
  ~RawServiceClient();

  /// Returns true with the reply, or false with `error` saying what failed (server error text,
  /// or no reply after N attempts of T ms from <endpoint>). Returns false at once on shutdown.
  bool Call(const msgs::WireMessage& request, msgs::WireMessage* reply, std::string* error,
            uint64_t* request_id_out = nullptr);
  /// The request id the next Call() will use (so the typed layer can put it in the header).
  uint64_t NextRequestId() const { return next_id_; }

  const std::string& Name() const { return name_; }
  const std::string& Endpoint() const { return endpoint_; }
  const ServiceStats& Stats() const { return stats_; }

 private:
  void Open();

  std::string name_;
  ServiceClientOptions options_;
  std::string endpoint_;
  std::unique_ptr<zmq::socket_t> socket_;
  uint64_t next_id_;
  ServiceStats stats_;
};

}  // namespace p2i::runtime
