/// @file pool_broker.cc
/// @brief Least-recently-used dispatch, re-queue on worker timeout.
#include "nodes/pool/pool_broker.h"

#include <stdexcept>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/zmq_context.h"

namespace p2i::nodes {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<zmq::message_t> ReadAll(zmq::socket_t& s, bool* got) {
  std::vector<zmq::message_t> frames;
  zmq::message_t m;
  *got = false;
  if (!s.recv(m, zmq::recv_flags::dontwait)) return frames;
  *got = true;
  bool more = m.more();
  frames.push_back(std::move(m));
  while (more) {
    zmq::message_t next;
    if (!s.recv(next, zmq::recv_flags::dontwait)) break;
    more = next.more();
    frames.push_back(std::move(next));
  }
  return frames;
}

void SendAll(zmq::socket_t& s, std::vector<zmq::message_t>& frames, size_t from) {
  for (size_t i = from; i < frames.size(); ++i)
    s.send(frames[i], i + 1 < frames.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
}

void Bind(zmq::socket_t& s, const std::string& endpoint, const std::string& what,
          std::string* actual) {
  runtime::CurveSecurity::Apply(s, endpoint, true, what);
  try {
    s.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error(what + ": cannot bind " + endpoint + ": " + e.what() +
                             " (another broker there? set the endpoint)");
  }
  *actual = s.get(zmq::sockopt::last_endpoint);
}

}  // namespace

void PoolBrokerOptions::Validate() const {
  if (frontend.empty()) throw std::invalid_argument("pool broker: frontend endpoint is empty");
  if (backend.empty()) throw std::invalid_argument("pool broker: backend endpoint is empty");
  if (worker_timeout.count() <= 0)
    throw std::invalid_argument("pool broker: worker_timeout must be > 0");
  if (idle_expiry.count() <= 0) throw std::invalid_argument("pool broker: idle_expiry must be > 0");
  if (max_queue == 0) throw std::invalid_argument("pool broker: max_queue must be > 0");
}

PoolBroker::PoolBroker(PoolBrokerOptions options, LogFn warn)
    : options_(std::move(options)),
      warn_(std::move(warn)),
      frontend_(runtime::ZmqContext(), zmq::socket_type::router),
      backend_(runtime::ZmqContext(), zmq::socket_type::router) {
  options_.Validate();
  for (auto* s : {&frontend_, &backend_}) {
    s->set(zmq::sockopt::linger, 0);
    s->set(zmq::sockopt::maxmsgsize, options_.max_message_bytes);
    s->set(zmq::sockopt::router_mandatory, false);
  }
  Bind(frontend_, options_.frontend, "pool broker frontend", &frontend_endpoint_);
  Bind(backend_, options_.backend, "pool broker backend", &backend_endpoint_);
}

std::vector<zmq::message_t> PoolBroker::Copy(const std::vector<zmq::message_t>& frames) {
  std::vector<zmq::message_t> out;
  for (const auto& f : frames) out.emplace_back(f.data(), f.size());
  return out;
}

void PoolBroker::OnFrontend() {
  for (int i = 0; i < 10000; ++i) {
    bool got = false;
    auto frames = ReadAll(frontend_, &got);
    if (!got) break;
    // [client][""][id][header][blobs...]
    if (frames.size() < 4 || frames[1].size() != 0 || frames[2].size() != 8) {
      ++stats_.refused;
      continue;
    }
    ++stats_.requests;
    if (queue_.size() >= options_.max_queue) {
      ++stats_.refused;
      std::vector<zmq::message_t> reply;
      reply.push_back(std::move(frames[0]));
      reply.emplace_back();
      reply.push_back(std::move(frames[2]));
      const std::string error = "pool broker: queue full (" + std::to_string(queue_.size()) +
                                " requests waiting for " + std::to_string(workers_.size()) +
                                " worker(s))";
      reply.emplace_back(error.data(), error.size());
      SendAll(frontend_, reply, 0);
      continue;
    }
    queue_.push_back(std::move(frames));
  }
  Dispatch();
}

void PoolBroker::OnBackend() {
  const auto now = Clock::now();
  for (int i = 0; i < 10000; ++i) {
    bool got = false;
    auto frames = ReadAll(backend_, &got);
    if (!got) break;
    if (frames.empty()) continue;
    const std::string id = frames[0].to_string();
    if (frames.size() == 2 && frames[1].to_string() == "READY") {
      auto [it, fresh] = workers_.try_emplace(id);
      it->second.last_seen = now;
      if (fresh) it->second.since = now;
      continue;
    }
    // A reply: [worker][client][""][request id][status][header][blobs...]
    if (frames.size() < 5) {
      ++stats_.refused;
      continue;
    }
    auto it = workers_.find(id);
    if (it != workers_.end()) {
      it->second.busy = false;
      it->second.request.clear();
      it->second.last_seen = now;
      it->second.since = now;
      ++it->second.served;
    } else {  // a worker presumed dead answered after all: serve with it again
      Worker w;
      w.last_seen = w.since = now;
      workers_[id] = std::move(w);
    }
    SendAll(frontend_, frames, 1);
    ++stats_.replies;
  }
  Dispatch();
}

void PoolBroker::OnTimer() {
  const auto now = Clock::now();
  for (auto it = workers_.begin(); it != workers_.end();) {
    Worker& w = it->second;
    if (w.busy && now - w.since > options_.worker_timeout) {
      warn_("pool worker did not answer within " + std::to_string(options_.worker_timeout.count()) +
            " ms: presumed dead, its request goes to another worker (" +
            std::to_string(workers_.size() - 1) + " worker(s) left)");
      queue_.push_front(std::move(w.request));
      ++stats_.requeued;
      ++stats_.workers_lost;
      it = workers_.erase(it);
    } else if (!w.busy && now - w.last_seen > options_.idle_expiry) {
      ++stats_.workers_lost;
      it = workers_.erase(it);
    } else {
      ++it;
    }
  }
  Dispatch();
}

void PoolBroker::Dispatch() {
  while (!queue_.empty()) {
    // The idle worker idle for longest (least recently used).
    Worker* best = nullptr;
    const std::string* best_id = nullptr;
    for (auto& [id, w] : workers_) {
      if (w.busy) continue;
      if (!best || w.since < best->since) {
        best = &w;
        best_id = &id;
      }
    }
    if (!best) break;
    auto frames = std::move(queue_.front());
    queue_.pop_front();
    best->request = Copy(frames);
    best->busy = true;
    best->since = Clock::now();
    backend_.send(zmq::buffer(*best_id), zmq::send_flags::sndmore);
    SendAll(backend_, frames, 0);
  }
  stats_.workers = workers_.size();
  stats_.queued = queue_.size();
}

}  // namespace p2i::nodes
