/// @file wire.h
/// @brief A message as it travels on the wire after its topic frame: a header frame and blobs.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace p2i::msgs {

using Bytes = std::vector<uint8_t>;
/// Image and other large payloads are shared, immutable byte buffers: the transport sends them
/// as their own frames without copying (it keeps a reference until ZeroMQ is done with them).
using Blob = std::shared_ptr<const Bytes>;

/// Multipart layout on a topic: [topic + '\0'][header][blob 0][blob 1]...
/// `header` is a serialized protobuf message whose field 1 is p2i.msgs.Header (so any receiver
/// can read type, version and sequence number before it knows the type).
struct WireMessage {
  std::string header;
  std::vector<Blob> blobs;
};

/// Size of the whole message in bytes (header + blobs), for size limits and statistics.
inline size_t WireSize(const WireMessage& m) {
  size_t n = m.header.size();
  for (const auto& b : m.blobs) n += b ? b->size() : 0;
  return n;
}

}  // namespace p2i::msgs
