/// @file ws_server.cc
/// @brief websocketpp server: handshake (subprotocol check), serverInfo + advertise on open,
/// subscribe / unsubscribe, bounded per-client sending, bad requests counted and answered.
#include "nodes/foxglove_bridge/ws_server.h"

#include <algorithm>
#include <random>
#include <set>
#include <stdexcept>

#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace p2i::foxglove_bridge {

using Server = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;

void WsServerOptions::Validate() const {
  if (port < 0 || port > 65535)
    throw std::invalid_argument("port: " + std::to_string(port) + " is not 0..65535");
  if (max_queue_bytes < 1024)
    throw std::invalid_argument("max_queue_bytes: must be >= 1024 bytes");
  if (max_client_message_bytes < 256)
    throw std::invalid_argument("max_client_message_bytes: must be >= 256 bytes");
}

// The websocketpp server and what only its I/O thread touches; the handlers below run there.
// Being WsServer's nested class, it updates the owner's stats and subscription counts.
struct WsServer::Impl {
  struct Client {
    std::map<uint32_t, uint32_t> subs;  // subscription id -> channel id
  };
  explicit Impl(WsServer& o) : owner(o) {}

  // Handshake: only clients offering the Foxglove subprotocol.
  bool Validate(Hdl hdl) {
    auto con = server.get_con_from_hdl(hdl);
    const auto& protos = con->get_requested_subprotocols();
    if (std::find(protos.begin(), protos.end(), kSubprotocol) == protos.end()) {
      ++owner.stats_.rejected;
      return false;
    }
    con->select_subprotocol(kSubprotocol);
    return true;
  }

  // A new client gets serverInfo and the channels advertised so far.
  void Open(Hdl hdl) {
    clients[hdl];
    ++owner.stats_.clients;
    ++owner.stats_.connections;
    websocketpp::lib::error_code ec;
    server.send(hdl, ServerInfoJson(owner.options_.name, session_id),
                websocketpp::frame::opcode::text, ec);
    std::vector<ChannelInfo> all;
    for (const auto& [id, c] : channels) all.push_back(c);
    if (!all.empty()) server.send(hdl, AdvertiseJson(all), websocketpp::frame::opcode::text, ec);
  }

  // A closed client's subscriptions no longer count.
  void Drop(Hdl hdl) {
    auto it = clients.find(hdl);
    if (it == clients.end()) return;
    {
      std::lock_guard<std::mutex> lock(owner.wanted_mutex_);
      for (const auto& [sub, ch] : it->second.subs) --owner.wanted_[ch];
    }
    clients.erase(it);
    --owner.stats_.clients;
  }

  void ReplyError(Hdl hdl, const std::string& text) {
    websocketpp::lib::error_code ec;
    server.send(hdl, StatusJson(2, text), websocketpp::frame::opcode::text, ec);
  }

  // A client request: bad and unsupported ones are counted and answered with a status.
  void Message(Hdl hdl, Server::message_ptr msg) {
    auto it = clients.find(hdl);
    if (it == clients.end()) return;
    if (msg->get_opcode() != websocketpp::frame::opcode::text) {
      ++owner.stats_.bad_requests;  // binary ops need capabilities this server does not advertise
      ReplyError(hdl, "binary client messages are not supported (no clientPublish capability)");
      return;
    }
    const ClientRequest r = ParseClientText(msg->get_payload());
    if (r.kind == ClientRequest::kBad) {
      ++owner.stats_.bad_requests;
      ReplyError(hdl, "ignored a bad request: " + r.error);
      return;
    }
    if (r.kind == ClientRequest::kUnsupported) {
      ++owner.stats_.unsupported;
      ReplyError(hdl, r.error);
      return;
    }
    if (r.kind == ClientRequest::kSubscribe) {
      Subscribe(hdl, r, &it->second);
    } else {
      Unsubscribe(hdl, r, &it->second);
    }
  }

  // The first subscription of a channel calls on_subscribed.
  void Subscribe(Hdl hdl, const ClientRequest& r, Client* client) {
    for (const auto& [sub, ch] : r.subscriptions) {
      if (!channels.count(ch)) {
        ++owner.stats_.bad_requests;
        ReplyError(hdl, "subscribe: unknown channel " + std::to_string(ch));
        continue;
      }
      if (client->subs.count(sub)) {
        ++owner.stats_.bad_requests;
        ReplyError(hdl, "subscribe: subscription id " + std::to_string(sub) + " is in use");
        continue;
      }
      client->subs[sub] = ch;
      bool first = false;
      {
        std::lock_guard<std::mutex> lock(owner.wanted_mutex_);
        first = owner.wanted_[ch]++ == 0;
      }
      if (first && owner.on_subscribed_) owner.on_subscribed_(ch);
    }
  }

  void Unsubscribe(Hdl hdl, const ClientRequest& r, Client* client) {
    for (uint32_t sub : r.unsubscribe_ids) {
      auto s = client->subs.find(sub);
      if (s == client->subs.end()) {
        ++owner.stats_.bad_requests;
        ReplyError(hdl, "unsubscribe: no subscription " + std::to_string(sub));
        continue;
      }
      {
        std::lock_guard<std::mutex> lock(owner.wanted_mutex_);
        --owner.wanted_[s->second];
      }
      client->subs.erase(s);
    }
  }

  // Binds the address and port of the options; returns the port bound (port 0: the one chosen).
  int Listen(const WsServerOptions& o) {
    websocketpp::lib::asio::error_code aec;
    const auto address = websocketpp::lib::asio::ip::address::from_string(o.address, aec);
    if (aec) {
      throw std::runtime_error("foxglove_bridge: address '" + o.address +
                               "' is not an IP address (e.g. 127.0.0.1 or 0.0.0.0)");
    }
    websocketpp::lib::error_code ec;
    server.listen(websocketpp::lib::asio::ip::tcp::endpoint(address, static_cast<uint16_t>(o.port)),
                  ec);
    if (ec) {
      throw std::runtime_error("foxglove_bridge: cannot listen on " + o.address + ":" +
                               std::to_string(o.port) + ": " + ec.message() +
                               " (set port:=N to another port, or port:=0 for any free one)");
    }
    const auto local = server.get_local_endpoint(aec);
    return aec ? o.port : local.port();
  }

  WsServer& owner;
  Server server;
  std::map<Hdl, Client, std::owner_less<Hdl>> clients;  // I/O thread only
  std::map<uint32_t, ChannelInfo> channels;               // I/O thread only
  std::string session_id;
};

WsServer::WsServer(WsServerOptions options, std::function<void(uint32_t)> on_subscribed)
    : impl_(std::make_unique<Impl>(*this)),
      options_(std::move(options)),
      on_subscribed_(std::move(on_subscribed)) {
  options_.Validate();
  std::random_device rd;
  impl_->session_id = std::to_string(rd()) + std::to_string(rd());
}

WsServer::~WsServer() { Stop(); }

void WsServer::Start() {
  Server& s = impl_->server;
  s.clear_access_channels(websocketpp::log::alevel::all);
  s.clear_error_channels(websocketpp::log::elevel::all);
  s.init_asio();
  s.set_reuse_addr(true);
  s.set_max_message_size(options_.max_client_message_bytes);
  Impl* impl = impl_.get();
  s.set_validate_handler([impl](Hdl hdl) { return impl->Validate(hdl); });
  s.set_open_handler([impl](Hdl hdl) { impl->Open(hdl); });
  s.set_close_handler([impl](Hdl hdl) { impl->Drop(hdl); });
  s.set_fail_handler([](Hdl) {});
  s.set_message_handler([impl](Hdl hdl, Server::message_ptr msg) { impl->Message(hdl, msg); });
  port_ = impl_->Listen(options_);
  s.start_accept();
  thread_ = std::thread([this] {
    try {
      impl_->server.run();
    } catch (...) {
    }
  });
}

void WsServer::Stop() {
  if (!thread_.joinable()) return;
  impl_->server.get_io_service().post([this] {
    websocketpp::lib::error_code ec;
    impl_->server.stop_listening(ec);
    for (auto& [hdl, c] : impl_->clients)
      impl_->server.close(hdl, websocketpp::close::status::going_away, "server stopping", ec);
  });
  // Give the close frames a moment, then stop the loop.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  impl_->server.stop();
  thread_.join();
}

void WsServer::SetChannels(std::vector<ChannelInfo> channels) {
  if (!thread_.joinable()) return;
  impl_->server.get_io_service().post([this, channels = std::move(channels)] {
    std::map<uint32_t, ChannelInfo> next;
    for (const auto& c : channels) next[c.id] = c;
    std::vector<ChannelInfo> added;
    std::vector<uint32_t> removed;
    for (const auto& [id, c] : next)
      if (!impl_->channels.count(id)) added.push_back(c);
    for (const auto& [id, c] : impl_->channels)
      if (!next.count(id)) removed.push_back(id);
    impl_->channels = std::move(next);
    websocketpp::lib::error_code ec;
    for (auto& [hdl, client] : impl_->clients) {
      for (auto s = client.subs.begin(); s != client.subs.end();) {
        if (std::find(removed.begin(), removed.end(), s->second) != removed.end()) {
          std::lock_guard<std::mutex> lock(wanted_mutex_);
          --wanted_[s->second];
          s = client.subs.erase(s);
        } else {
          ++s;
        }
      }
      if (!removed.empty())
        impl_->server.send(hdl, UnadvertiseJson(removed), websocketpp::frame::opcode::text, ec);
      if (!added.empty())
        impl_->server.send(hdl, AdvertiseJson(added), websocketpp::frame::opcode::text, ec);
    }
  });
}

bool WsServer::Wanted(uint32_t channel) const {
  std::lock_guard<std::mutex> lock(wanted_mutex_);
  const auto it = wanted_.find(channel);
  return it != wanted_.end() && it->second > 0;
}

void WsServer::Publish(uint32_t channel, uint64_t timestamp_ns,
                       std::shared_ptr<const std::string> payload) {
  if (!thread_.joinable()) return;
  // Bound what waits for the I/O thread too (it may fall behind under load).
  if (pending_bytes_.load() + payload->size() > 4 * options_.max_queue_bytes) {
    ++stats_.dropped;
    return;
  }
  pending_bytes_ += payload->size();
  impl_->server.get_io_service().post([this, channel, timestamp_ns, payload] {
    pending_bytes_ -= payload->size();
    for (auto& [hdl, client] : impl_->clients) {
      for (const auto& [sub, ch] : client.subs) {
        if (ch != channel) continue;
        websocketpp::lib::error_code ec;
        auto con = impl_->server.get_con_from_hdl(hdl, ec);
        if (ec || !con) continue;
        const size_t queued = con->get_buffered_amount();
        if (queued > 0 && queued + payload->size() > options_.max_queue_bytes) {
          ++stats_.dropped;
          continue;
        }
        const std::string frame = MessageDataFrame(sub, timestamp_ns, *payload);
        con->send(frame, websocketpp::frame::opcode::binary);
        ++stats_.messages_sent;
        stats_.bytes_sent += frame.size();
      }
    }
  });
}

}  // namespace p2i::foxglove_bridge
