/// @file raw_service.cc
/// @brief ROUTER server and Lazy Pirate DEALER client.
#include "nodes/runtime/raw_service.h"

#include <cstring>
#include <random>
#include <stdexcept>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/peer_registry.h"
#include "nodes/runtime/shutdown.h"
#include "nodes/runtime/wire_io.h"
#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {
namespace {

zmq::message_t IdFrame(uint64_t id) {
  uint8_t b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<uint8_t>(id >> (8 * i));
  return zmq::message_t(b, 8);
}

bool ParseId(const zmq::message_t& f, uint64_t* id) {
  if (f.size() != 8) return false;
  const auto* b = static_cast<const uint8_t*>(f.data());
  *id = 0;
  for (int i = 0; i < 8; ++i) *id |= static_cast<uint64_t>(b[i]) << (8 * i);
  return true;
}

}  // namespace

// ---------------------------------------------------------------------------------- server

RawServiceServer::RawServiceServer(std::string resolved_name, std::string type_name,
                                   std::string node_name, ServiceServerOptions options,
                                   Handler handler)
    : name_(std::move(resolved_name)),
      options_(std::move(options)),
      handler_(std::move(handler)),
      socket_(ZmqContext(), options_.worker_of.empty() ? zmq::socket_type::router
                                                       : zmq::socket_type::dealer) {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.set(zmq::sockopt::maxmsgsize, options_.max_message_bytes);
  if (!options_.worker_of.empty()) {  // pool worker: the broker binds, the worker connects
    endpoint_ = options_.worker_of;
    CurveSecurity::Apply(socket_, endpoint_, false, "pool worker of service '" + name_ + "'");
    try {
      socket_.connect(endpoint_);
    } catch (const zmq::error_t& e) {
      throw std::runtime_error("service '" + name_ + "': cannot connect to the pool broker at " +
                               endpoint_ + ": " + e.what());
    }
    Heartbeat();
    return;
  }
  endpoint_ = options_.endpoint.empty() ? DefaultEndpoint("service", name_) : options_.endpoint;
  // A reply to a client that has gone away (Lazy Pirate reopened it) is dropped silently.
  socket_.set(zmq::sockopt::router_mandatory, false);
  Registry::CheckEndpointFree(endpoint_, "service '" + name_ + "'");
  CurveSecurity::Apply(socket_, endpoint_, true, "service '" + name_ + "'");
  try {
    socket_.bind(endpoint_);
    endpoint_ = socket_.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("service '" + name_ + "': cannot bind " + endpoint_ + ": " +
                             e.what() + " (another server on this endpoint? set the service's "
                             "endpoint parameter)");
  }
  RegistryEntry entry{"service", name_, type_name, endpoint_, node_name, 0, "", ""};
  if (options_.endpoint.empty())  // multi-host launch: also on this host's address
    entry.remote_endpoint = BindHostEndpoint(socket_, "service '" + name_ + "'");
  registry_path_ = Registry::Register(entry);
}

RawServiceServer::~RawServiceServer() {
  Registry::Unregister(registry_path_);
  socket_.close();
}

void RawServiceServer::Heartbeat() {
  if (options_.worker_of.empty()) return;
  socket_.send(zmq::buffer(std::string("READY")), zmq::send_flags::dontwait);
}

int RawServiceServer::Drain() {
  int handled = 0;
  for (int i = 0; i < 10000; ++i) {
    frames_.clear();
    zmq::message_t first;
    if (!socket_.recv(first, zmq::recv_flags::dontwait)) break;
    frames_.push_back(std::move(first));
    RecvRest(socket_, &frames_);
    // [identity][""][id][header][blobs...]
    uint64_t id = 0;
    if (frames_.size() < 4 || frames_[1].size() != 0 || !ParseId(frames_[2], &id)) {
      stats_.malformed.fetch_add(1, std::memory_order_relaxed);
      last_error_ = "malformed request envelope (" + std::to_string(frames_.size()) + " frames)";
      continue;  // cannot reply meaningfully without a request id
    }
    msgs::WireMessage request, reply;
    FramesToWire(frames_, 3, &request);
    std::string error;
    bool ok = false;
    try {
      ok = handler_(request, id, &reply, &error);
    } catch (const std::exception& e) {
      ok = false;
      error = std::string("handler threw: ") + e.what();
    }
    stats_.requests.fetch_add(1, std::memory_order_relaxed);
    if (!ok) {
      stats_.errors.fetch_add(1, std::memory_order_relaxed);
      if (error.empty()) error = "request failed";
      last_error_ = error;
    }
    socket_.send(frames_[0], zmq::send_flags::sndmore);  // identity
    socket_.send(zmq::message_t(), zmq::send_flags::sndmore);
    socket_.send(IdFrame(id), zmq::send_flags::sndmore);
    if (ok) {
      socket_.send(zmq::message_t(), zmq::send_flags::sndmore);
      SendWire(socket_, reply);
    } else {
      socket_.send(zmq::buffer(error), zmq::send_flags::none);
    }
    ++handled;
  }
  return handled;
}

// ---------------------------------------------------------------------------------- client

RawServiceClient::RawServiceClient(std::string resolved_name, ServiceClientOptions options)
    : name_(std::move(resolved_name)), options_(std::move(options)) {
  endpoint_ = options_.endpoint.empty() ? DefaultEndpoint("service", name_) : options_.endpoint;
  // Random start so ids of a restarted client do not collide with replies still in flight.
  next_id_ = (std::random_device{}() & 0xffffff) * 1000ull + 1;
  Open();
}

RawServiceClient::~RawServiceClient() {
  if (socket_) socket_->close();
}

void RawServiceClient::Open() {
  if (socket_) socket_->close();
  socket_ = std::make_unique<zmq::socket_t>(ZmqContext(), zmq::socket_type::dealer);
  socket_->set(zmq::sockopt::linger, 0);
  if (options_.resolver) {  // multi-host: the server may have moved (respawn, other host)
    const std::string found = options_.resolver();
    if (!found.empty()) endpoint_ = found;
  }
  CurveSecurity::Apply(*socket_, endpoint_, false, "client of service '" + name_ + "'");
  socket_->connect(endpoint_);
}

bool RawServiceClient::Call(const msgs::WireMessage& request, msgs::WireMessage* reply,
                            std::string* error, uint64_t* request_id_out) {
  const uint64_t id = next_id_++;
  if (request_id_out) *request_id_out = id;
  stats_.requests.fetch_add(1, std::memory_order_relaxed);
  const int attempts = 1 + std::max(0, options_.retries);
  for (int attempt = 0; attempt < attempts; ++attempt) {
    if (attempt > 0) {
      Open();
      stats_.reconnects.fetch_add(1, std::memory_order_relaxed);
    }
    socket_->send(zmq::message_t(), zmq::send_flags::sndmore);
    socket_->send(IdFrame(id), zmq::send_flags::sndmore);
    SendWire(*socket_, request);
    const auto deadline = std::chrono::steady_clock::now() + options_.timeout;
    while (true) {
      if (Shutdown::Requested()) {
        *error = "service '" + name_ + "': shutdown requested";
        stats_.errors.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) break;
      zmq::pollitem_t items[] = {{socket_->handle(), 0, ZMQ_POLLIN, 0},
                                 {nullptr, Shutdown::WakeFd(), ZMQ_POLLIN, 0}};
      Poll(items, 2, std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now));
      if (!(items[0].revents & ZMQ_POLLIN)) continue;
      std::vector<zmq::message_t> frames;
      zmq::message_t first;
      if (!socket_->recv(first, zmq::recv_flags::dontwait)) continue;
      frames.push_back(std::move(first));
      RecvRest(*socket_, &frames);
      // [""][id][status][header][blobs...]
      uint64_t got = 0;
      if (frames.size() < 3 || frames[0].size() != 0 || !ParseId(frames[1], &got)) {
        stats_.malformed.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (got != id) {
        stats_.stale_replies.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      if (frames[2].size() != 0) {
        *error = "service '" + name_ + "' replied with an error: " + frames[2].to_string();
        stats_.errors.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
      if (!FramesToWire(frames, 3, reply)) {
        stats_.malformed.fetch_add(1, std::memory_order_relaxed);
        *error = "service '" + name_ + "': reply without a header frame";
        stats_.errors.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
      return true;
    }
    stats_.timeouts.fetch_add(1, std::memory_order_relaxed);
  }
  // Leave a fresh socket behind so the next call does not receive this call's late reply.
  Open();
  stats_.reconnects.fetch_add(1, std::memory_order_relaxed);
  stats_.errors.fetch_add(1, std::memory_order_relaxed);
  *error = "service '" + name_ + "': no reply from " + endpoint_ + " after " +
           std::to_string(attempts) + " attempt(s) of " +
           std::to_string(options_.timeout.count()) + " ms (is the server running?)";
  return false;
}

}  // namespace p2i::runtime
