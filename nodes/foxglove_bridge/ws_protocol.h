/// @file ws_protocol.h
/// @brief The Foxglove WebSocket protocol, subprotocol "foxglove.websocket.v1"
/// (https://github.com/foxglove/ws-protocol): the server's JSON messages, parsing of client
/// requests and the binary message-data frame. Pure functions, no sockets.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p2i::foxglove_bridge {

inline constexpr const char* kSubprotocol = "foxglove.websocket.v1";
inline constexpr uint8_t kMessageDataOpcode = 0x01;

/// One advertised channel.
struct ChannelInfo {
  uint32_t id = 0;
  std::string topic;
  std::string encoding = "protobuf";
  std::string schema_name;     ///< e.g. "p2i.msgs.pb.RgbdFrame", "foxglove.RawImage"
  std::string schema;          ///< serialized FileDescriptorSet (base64-encoded on the wire)
  std::string source_topic;    ///< the p2i topic it comes from (not sent)
};

std::string ServerInfoJson(const std::string& name, const std::string& session_id);
std::string AdvertiseJson(const std::vector<ChannelInfo>& channels);
std::string UnadvertiseJson(const std::vector<uint32_t>& channel_ids);
/// level: 0 info, 1 warning, 2 error.
std::string StatusJson(int level, const std::string& message);

/// A client request, parsed. kind kBad carries the reason (the caller counts and reports it).
struct ClientRequest {
  enum Kind { kSubscribe, kUnsubscribe, kUnsupported, kBad } kind = kBad;
  std::vector<std::pair<uint32_t, uint32_t>> subscriptions;  ///< (subscription id, channel id)
  std::vector<uint32_t> unsubscribe_ids;
  std::string op;      ///< the "op" given (kUnsupported)
  std::string error;   ///< why it is bad
};
/// Never throws: anything that is not a well-formed subscribe / unsubscribe is kBad or
/// kUnsupported with a reason.
ClientRequest ParseClientText(const std::string& text);

/// [0x01][u32 subscription id][u64 timestamp ns][payload], little-endian.
std::string MessageDataFrame(uint32_t subscription_id, uint64_t timestamp_ns,
                             const std::string& payload);

std::string Base64(const std::string& bytes);

}  // namespace p2i::foxglove_bridge
