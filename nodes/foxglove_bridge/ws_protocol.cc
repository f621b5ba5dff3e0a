/// @file ws_protocol.cc
/// @brief JSON builders/parsers of foxglove.websocket.v1 and the binary message frame.
#include "nodes/foxglove_bridge/ws_protocol.h"

#include <cstring>

#include <nlohmann/json.hpp>

namespace p2i::foxglove_bridge {

using nlohmann::json;

std::string Base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    out += t[v >> 18];
    out += t[(v >> 12) & 63];
    out += t[(v >> 6) & 63];
    out += t[v & 63];
  }
  if (i + 1 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16;
    out += t[v >> 18];
    out += t[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
    out += t[v >> 18];
    out += t[(v >> 12) & 63];
    out += t[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string ServerInfoJson(const std::string& name, const std::string& session_id) {
  return json{{"op", "serverInfo"},
              {"name", name},
              {"capabilities", json::array()},
              {"supportedEncodings", json::array()},
              {"metadata", json::object()},
              {"sessionId", session_id}}
      .dump();
}

std::string AdvertiseJson(const std::vector<ChannelInfo>& channels) {
  json list = json::array();
  for (const auto& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", Base64(c.schema)},
                    {"schemaEncoding", "protobuf"}});
  }
  return json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string UnadvertiseJson(const std::vector<uint32_t>& ids) {
  return json{{"op", "unadvertise"}, {"channelIds", ids}}.dump();
}

std::string StatusJson(int level, const std::string& message) {
  return json{{"op", "status"}, {"level", level}, {"message", message}}.dump();
}

namespace {

bool GetU32(const json& j, const char* key, uint32_t* out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_unsigned()) return false;
  const auto v = it->get<uint64_t>();
  if (v > 0xffffffffull) return false;
  *out = static_cast<uint32_t>(v);
  return true;
}

}  // namespace

ClientRequest ParseClientText(const std::string& text) {
  ClientRequest r;
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    r.error = "not a JSON object";
    return r;
  }
  const auto op = j.find("op");
  if (op == j.end() || !op->is_string()) {
    r.error = "no \"op\" string";
    return r;
  }
  r.op = op->get<std::string>();
  if (r.op == "subscribe") {
    const auto subs = j.find("subscriptions");
    if (subs == j.end() || !subs->is_array()) {
      r.error = "subscribe without a \"subscriptions\" array";
      return r;
    }
    for (const auto& s : *subs) {
      uint32_t id = 0, channel = 0;
      if (!s.is_object() || !GetU32(s, "id", &id) || !GetU32(s, "channelId", &channel)) {
        r.error = "a subscription needs unsigned \"id\" and \"channelId\"";
        r.subscriptions.clear();
        return r;
      }
      r.subscriptions.emplace_back(id, channel);
    }
    r.kind = ClientRequest::kSubscribe;
    return r;
  }
  if (r.op == "unsubscribe") {
    const auto ids = j.find("subscriptionIds");
    if (ids == j.end() || !ids->is_array()) {
      r.error = "unsubscribe without a \"subscriptionIds\" array";
      return r;
    }
    for (const auto& v : *ids) {
      if (!v.is_number_unsigned() || v.get<uint64_t>() > 0xffffffffull) {
        r.error = "subscriptionIds must be unsigned 32-bit integers";
        r.unsubscribe_ids.clear();
        return r;
      }
      r.unsubscribe_ids.push_back(static_cast<uint32_t>(v.get<uint64_t>()));
    }
    r.kind = ClientRequest::kUnsubscribe;
    return r;
  }
  r.kind = ClientRequest::kUnsupported;
  r.error = "op \"" + r.op + "\" is not supported by this server (capabilities: none)";
  return r;
}

std::string MessageDataFrame(uint32_t subscription_id, uint64_t timestamp_ns,
                             const std::string& payload) {
  std::string f(13 + payload.size(), '\0');
  f[0] = static_cast<char>(kMessageDataOpcode);
  std::memcpy(&f[1], &subscription_id, 4);  // little-endian host (x86-64, aarch64)
  std::memcpy(&f[5], &timestamp_ns, 8);
  std::memcpy(&f[13], payload.data(), payload.size());
  return f;
}

}  // namespace p2i::foxglove_bridge
