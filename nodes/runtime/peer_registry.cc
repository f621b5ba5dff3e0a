/// @file peer_registry.cc
/// @brief Registry server thread, peer queries and the peer watcher thread.
#include "nodes/runtime/peer_registry.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "nodes/runtime/curve_auth.h"
#include "nodes/runtime/zmq_context.h"

namespace p2i::runtime {
namespace {

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string part;
  while (std::getline(ss, part, sep)) {
    const auto b = part.find_first_not_of(" \t");
    if (b == std::string::npos) continue;
    out.push_back(part.substr(b, part.find_last_not_of(" \t") - b + 1));
  }
  return out;
}

std::string Serialize(const std::vector<RegistryEntry>& entries) {
  std::string out;
  for (const auto& e : entries) {
    out += e.kind + "\t" + e.name + "\t" + e.type + "\t" +
           (e.remote_endpoint.empty() ? e.endpoint : e.remote_endpoint) + "\t" + e.node + "\t" +
           std::to_string(e.pid) + "\n";
  }
  return out;
}

std::vector<RegistryEntry> Parse(const std::string& text, const std::string& host) {
  std::vector<RegistryEntry> out;
  for (const auto& line : Split(text, '\n')) {
    const auto f = Split(line, '\t');
    if (f.size() != 6) continue;
    RegistryEntry e;
    e.kind = f[0];
    e.name = f[1];
    e.type = f[2];
    e.endpoint = f[3];
    e.node = f[4];
    e.pid = std::atoi(f[5].c_str());
    e.host = host;
    out.push_back(e);
  }
  return out;
}

}  // namespace

std::string HostAddress() {
  const char* env = std::getenv("P2I_HOST_ADDRESS");
  return env ? env : "";
}

std::vector<std::string> PeerRegistries() {
  const char* env = std::getenv("P2I_PEERS");
  return env ? Split(env, ',') : std::vector<std::string>{};
}

std::string BindHostEndpoint(zmq::socket_t& socket, const std::string& what) {
  const std::string address = HostAddress();
  if (address.empty()) return "";
  const std::string endpoint = "tcp://" + address + ":*";
  CurveSecurity::Apply(socket, endpoint, true, what);
  try {
    socket.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error(what + ": cannot bind " + endpoint + " (P2I_HOST_ADDRESS): " +
                             e.what() + "; is " + address + " an address of this host?");
  }
  return socket.get(zmq::sockopt::last_endpoint);
}

// ------------------------------------------------------------------------- registry server

struct RegistryServer::Impl {
  zmq::socket_t socket{ZmqContext(), zmq::socket_type::router};
  std::atomic<bool> stop{false};
  std::thread thread;
  void Loop() {
    while (!stop) {
      zmq::pollitem_t item{socket.handle(), 0, ZMQ_POLLIN, 0};
      try {
        zmq::poll(&item, 1, std::chrono::milliseconds(100));
      } catch (const zmq::error_t&) {
        continue;
      }
      if (!(item.revents & ZMQ_POLLIN)) continue;
      std::vector<zmq::message_t> frames;
      zmq::message_t m;
      while (socket.recv(m, zmq::recv_flags::dontwait)) {
        const bool more = m.more();
        frames.push_back(std::move(m));
        if (!more) break;
      }
      // [identity][""][request]
      if (frames.size() != 3 || frames[2].to_string() != "LIST") continue;
      const std::string text = Serialize(Registry::List());
      socket.send(frames[0], zmq::send_flags::sndmore);
      socket.send(zmq::message_t(), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(std::string("OK")), zmq::send_flags::sndmore);
      socket.send(zmq::buffer(text), zmq::send_flags::none);
    }
  }
};

RegistryServer::RegistryServer(const std::string& endpoint) : impl_(std::make_unique<Impl>()) {
  impl_->socket.set(zmq::sockopt::linger, 0);
  impl_->socket.set(zmq::sockopt::maxmsgsize, int64_t{4096});
  CurveSecurity::Apply(impl_->socket, endpoint, true, "registry server");
  try {
    impl_->socket.bind(endpoint);
  } catch (const zmq::error_t& e) {
    throw std::runtime_error("registry server: cannot bind " + endpoint + ": " + e.what() +
                             " (port in use, or not an address of this host?)");
  }
  endpoint_ = impl_->socket.get(zmq::sockopt::last_endpoint);
  impl_->thread = std::thread([this] { impl_->Loop(); });
}

RegistryServer::~RegistryServer() {
  impl_->stop = true;
  impl_->thread.join();
  impl_->socket.close();
}

bool QueryPeer(const std::string& registry_endpoint, std::chrono::milliseconds timeout,
               std::vector<RegistryEntry>* entries, std::string* error) {
  zmq::socket_t s(ZmqContext(), zmq::socket_type::dealer);
  s.set(zmq::sockopt::linger, 0);
  try {
    CurveSecurity::Apply(s, registry_endpoint, false, "peer registry " + registry_endpoint);
    s.connect(registry_endpoint);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  s.send(zmq::message_t(), zmq::send_flags::sndmore);
  s.send(zmq::buffer(std::string("LIST")), zmq::send_flags::none);
  zmq::pollitem_t item{s.handle(), 0, ZMQ_POLLIN, 0};
  zmq::poll(&item, 1, timeout);
  std::vector<zmq::message_t> frames;
  zmq::message_t m;
  while (s.recv(m, zmq::recv_flags::dontwait)) {
    const bool more = m.more();
    frames.push_back(std::move(m));
    if (!more) break;
  }
  if (frames.size() != 3 || frames[1].to_string() != "OK") {
    *error = "no reply from peer registry " + registry_endpoint + " within " +
             std::to_string(timeout.count()) + " ms (is `p2i launch` running on that host?)";
    return false;
  }
  const auto got = Parse(frames[2].to_string(), registry_endpoint);
  entries->insert(entries->end(), got.begin(), got.end());
  return true;
}

std::vector<RegistryEntry> ListGraph(const std::vector<std::string>& local_run_dirs,
                                     const std::vector<std::string>& peers,
                                     std::chrono::milliseconds timeout,
                                     std::vector<std::string>* errors) {
  std::vector<RegistryEntry> out;
  for (const auto& dir : local_run_dirs) {
    const auto local = Registry::ListDir(dir);
    out.insert(out.end(), local.begin(), local.end());
  }
  for (const auto& peer : peers) {
    std::string error;
    if (!QueryPeer(peer, timeout, &out, &error) && errors) errors->push_back(error);
  }
  return out;
}

std::vector<std::string> ReachableEndpoints(const std::vector<RegistryEntry>& entries,
                                            const std::string& kind, const std::string& name) {
  std::vector<std::string> out;
  for (const auto& e : entries) {
    if (e.kind != kind || e.name != name) continue;
    if (!e.host.empty() && e.endpoint.rfind("tcp://", 0) != 0) continue;
    if (std::find(out.begin(), out.end(), e.endpoint) == out.end()) out.push_back(e.endpoint);
  }
  return out;
}

std::string FindServiceEndpoint(const std::string& name, const std::vector<std::string>& peers,
                                std::chrono::milliseconds timeout) {
  for (const auto& e : Registry::List())
    if (e.kind == "service" && e.name == name) return e.endpoint;
  std::vector<RegistryEntry> remote;
  for (const auto& peer : peers) {
    std::string error;
    QueryPeer(peer, timeout, &remote, &error);
  }
  const auto eps = ReachableEndpoints(remote, "service", name);
  return eps.empty() ? "" : eps.back();
}

// ------------------------------------------------------------------------- watcher

struct PeerWatcher::Impl {
  std::vector<std::string> peers;
  std::chrono::milliseconds period;
  std::mutex mutex;
  struct Watched {
    std::string kind, name;
    Callback cb;
    std::set<std::string> known;
  };
  std::vector<std::shared_ptr<Watched>> watched;
  std::atomic<bool> stop{false};
  std::thread thread;

  void Loop() {
    while (!stop) {
      std::vector<std::shared_ptr<Watched>> now;
      {
        std::lock_guard<std::mutex> lock(mutex);
        now = watched;
      }
      if (!now.empty()) {
        std::vector<RegistryEntry> entries;
        for (const auto& peer : peers) {
          if (stop) return;
          std::string error;
          QueryPeer(peer, std::chrono::milliseconds(300), &entries, &error);
        }
        for (auto& w : now) {
          std::vector<std::string> fresh;
          for (const auto& ep : ReachableEndpoints(entries, w->kind, w->name))
            if (w->known.insert(ep).second) fresh.push_back(ep);
          if (!fresh.empty() && !stop) w->cb(fresh);
        }
      }
      const auto until = std::chrono::steady_clock::now() + period;
      while (!stop && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
};

PeerWatcher::PeerWatcher(std::vector<std::string> peers, std::chrono::milliseconds period)
    : impl_(std::make_unique<Impl>()) {
  impl_->peers = std::move(peers);
  impl_->period = period;
  impl_->thread = std::thread([this] { impl_->Loop(); });
}

PeerWatcher::~PeerWatcher() {
  impl_->stop = true;
  impl_->thread.join();
}

void PeerWatcher::Watch(const std::string& kind, const std::string& name, Callback cb) {
  auto w = std::make_shared<Impl::Watched>();
  w->kind = kind;
  w->name = name;
  w->cb = std::move(cb);
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->watched.push_back(w);
}

}  // namespace p2i::runtime
