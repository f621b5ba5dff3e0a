/// @file inline_blobs.h
/// @brief A p2i WireMessage (header frame + blob frames) <-> one self-contained protobuf message
/// with each blob's bytes inline: how messages are stored in MCAP files and sent to Foxglove
/// clients, so any protobuf reader with the embedded schema decodes them whole.
///
/// The recorded schema is p2i.proto with one field added to ImageInfo, `bytes data = 8` (the
/// image's pixels, `height x step` bytes). It is added to the descriptor at run time
/// (RecordingSchema), not to msgs/p2i.proto: on the ZeroMQ wire pixels stay in blob frames.
/// A recorded message starts with the unchanged header frame; the pixels follow as protobuf
/// fields that merge into its ImageInfos (protobuf concatenation = merge).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include "msgs/wire.h"

namespace p2i::recording {

/// The serialized FileDescriptorSet recorded for a p2i type: p2i.proto with ImageInfo.data.
/// For any other type (foxglove.*): FileDescriptorSetFor(type).
std::string RecordingSchema(const google::protobuf::Descriptor* type);

/// The recorded message for `m` (its type given by `type`, a p2i.msgs.pb message): writes
/// the size into *size and returns a writer of exactly that many bytes. Null + error if the
/// header does not parse or an ImageInfo names a missing blob.
class InlinedMessage {
 public:
  static std::unique_ptr<InlinedMessage> Make(const google::protobuf::Descriptor* type,
                                              const msgs::WireMessage& m, std::string* error);
  virtual ~InlinedMessage() = default;
  virtual size_t Size() const = 0;
  virtual void WriteTo(uint8_t* dst) const = 0;
  std::string ToString() const {
    std::string s(Size(), '\0');
    WriteTo(reinterpret_cast<uint8_t*>(s.data()));
    return s;
  }
};

/// The inverse: parses recorded bytes of p2i type `type_name` (e.g. "p2i.msgs.pb.RgbdFrame"),
/// moves each ImageInfo.data into blob blob_index and re-serializes the header frame. False +
/// error for unknown types, unparsable data, duplicate or non-contiguous blob indexes.
bool ExtractBlobs(const std::string& type_name, const uint8_t* data, size_t size,
                  msgs::WireMessage* out, std::string* error);

}  // namespace p2i::recording
