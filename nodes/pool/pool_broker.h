/// @file pool_broker.h
/// @brief Load-balancing broker of one service over a pool of workers (ZeroMQ ROUTER/ROUTER,
/// docs/POOL.md). Torch-free, no node: the p2i_pool node drives it; tests drive it directly.
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <zmq.hpp>

namespace p2i::nodes {

struct PoolBrokerOptions {
  std::string frontend;   ///< bound ROUTER the clients call (the service's endpoint)
  std::string backend;    ///< bound ROUTER the workers connect to (their `pool` parameter)
  /// A worker that has not answered a request within this time is presumed dead: it is dropped
  /// and the request goes to another worker (the clients' own retries cover the rest).
  std::chrono::milliseconds worker_timeout{3000};
  /// An idle worker silent for this long (no heartbeat) is dropped.
  std::chrono::milliseconds idle_expiry{3500};
  int64_t max_message_bytes = 64ll << 20;  ///< ZMQ_MAXMSGSIZE on both sockets
  size_t max_queue = 10000;                ///< requests waiting beyond this are refused
  void Validate() const;                   ///< throws std::invalid_argument naming the field
};

struct PoolBrokerStats {
  uint64_t requests = 0;    ///< from clients
  uint64_t replies = 0;     ///< forwarded back to clients
  uint64_t requeued = 0;    ///< requests taken back from a presumed-dead worker
  uint64_t workers_lost = 0;
  uint64_t refused = 0;     ///< malformed, or the queue was full
  size_t workers = 0;       ///< known now
  size_t queued = 0;        ///< waiting for a worker now
};

/// Clients send [""][id][header][blobs] to the frontend (a service client needs no change);
/// workers (RawServiceServer with `worker_of`) send ["READY"] when idle and reply
/// [client][""][id][status][...]. Each request goes to the idle worker that has waited longest;
/// each worker has at most one request in flight. Thread-safety: one owner thread (the one
/// calling OnFrontend/OnBackend/OnTimer).
class PoolBroker {
 public:
  using LogFn = std::function<void(const std::string&)>;
  PoolBroker(PoolBrokerOptions options, LogFn warn);
  zmq::socket_t& Frontend() { return frontend_; }
  zmq::socket_t& Backend() { return backend_; }
  const std::string& FrontendEndpoint() const { return frontend_endpoint_; }
  const std::string& BackendEndpoint() const { return backend_endpoint_; }
  void OnFrontend();  ///< drain client requests
  void OnBackend();   ///< drain worker messages
  void OnTimer();     ///< presumed-dead workers (call every ~100 ms)
  const PoolBrokerStats& Stats() const { return stats_; }

 private:
  struct Worker {
    std::chrono::steady_clock::time_point last_seen, since;  // since = dispatch or idle start
    bool busy = false;
    std::vector<zmq::message_t> request;  // in flight (kept to re-queue)
    uint64_t served = 0;
  };
  void Dispatch();
  static std::vector<zmq::message_t> Copy(const std::vector<zmq::message_t>& frames);

  PoolBrokerOptions options_;
  LogFn warn_;
  zmq::socket_t frontend_, backend_;
  std::string frontend_endpoint_, backend_endpoint_;
  std::map<std::string, Worker> workers_;  // by ZeroMQ routing id
  std::deque<std::vector<zmq::message_t>> queue_;  // [client][""][id][header][blobs]
  PoolBrokerStats stats_;
};

}  // namespace p2i::nodes
