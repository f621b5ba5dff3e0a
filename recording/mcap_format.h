/// @file mcap_format.h
/// @brief MCAP record layout (https://mcap.dev/spec): magic, opcodes and the records p2i reads
/// and writes, plus little-endian field encoding helpers.
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <vector>

namespace p2i::recording::mcap {

/// 0x89 'M' 'C' 'A' 'P' '0' '\r' '\n' at the start and the end of every file.
inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

enum class Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

struct Schema {
  uint16_t id = 0;           ///< never 0
  std::string name;          ///< e.g. "p2i.msgs.pb.RgbdFrame"
  std::string encoding;      ///< "protobuf" (data = a serialized FileDescriptorSet)
  std::string data;
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  ///< "protobuf"
  std::map<std::string, std::string> metadata;
};

/// A message as read (data points into the reader's chunk buffer: valid during the callback).
struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0;      ///< ns: when the recorder received it
  uint64_t publish_time = 0;  ///< ns: when it was published
  const uint8_t* data = nullptr;
  size_t size = 0;
};

struct ChunkIndex {
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  uint64_t chunk_start_offset = 0;
  uint64_t chunk_length = 0;  ///< whole record incl. opcode and length
  std::map<uint16_t, uint64_t> message_index_offsets;
  uint64_t message_index_length = 0;
  std::string compression;
  uint64_t compressed_size = 0;
  uint64_t uncompressed_size = 0;
};

struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0;
  uint32_t attachment_count = 0;
  uint32_t metadata_count = 0;
  uint32_t chunk_count = 0;
  uint64_t message_start_time = 0;
  uint64_t message_end_time = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

/// Appends little-endian fields to a byte buffer.
class Encoder {
 public:
  explicit Encoder(std::string* out) : out_(out) {}
  void U8(uint8_t v) { out_->push_back(static_cast<char>(v)); }
  void U16(uint16_t v) { Raw(&v, 2); }
  void U32(uint32_t v) { Raw(&v, 4); }
  void U64(uint64_t v) { Raw(&v, 8); }
  void Str(const std::string& s) {
    U32(static_cast<uint32_t>(s.size()));
    out_->append(s);
  }
  void StrMap(const std::map<std::string, std::string>& m);
  void U16U64Map(const std::map<uint16_t, uint64_t>& m);
  void Raw(const void* p, size_t n) { out_->append(static_cast<const char*>(p), n); }

 private:
  std::string* out_;  // little-endian host assumed (x86-64, aarch64); checked in mcap_format.cc
};

/// Reads little-endian fields from a bounded span; every read checks the bounds and sets
/// ok() = false instead of reading past the end (malformed files never crash the reader).
class Decoder {
 public:
  Decoder(const uint8_t* p, size_t n) : p_(p), end_(p + n) {}
  uint8_t U8();
  uint16_t U16();
  uint32_t U32();
  uint64_t U64();
  std::string Str();
  std::map<std::string, std::string> StrMap();
  std::map<uint16_t, uint64_t> U16U64Map();
  /// `n` bytes; nullptr (and !ok()) if fewer remain.
  const uint8_t* Take(size_t n);
  size_t Remaining() const { return static_cast<size_t>(end_ - p_); }
  bool ok() const { return ok_; }

 private:
  template <typename T>
  T Fixed();
  const uint8_t* p_;
  const uint8_t* end_;
  bool ok_ = true;
};

/// Record bodies (the content after opcode + length).
std::string EncodeSchema(const Schema& s);
std::string EncodeChannel(const Channel& c);
std::string EncodeChunkIndex(const ChunkIndex& c);
std::string EncodeStatistics(const Statistics& s);
bool DecodeSchema(const uint8_t* p, size_t n, Schema* out);
bool DecodeChannel(const uint8_t* p, size_t n, Channel* out);
bool DecodeMessage(const uint8_t* p, size_t n, Message* out);
bool DecodeChunkIndex(const uint8_t* p, size_t n, ChunkIndex* out);
bool DecodeStatistics(const uint8_t* p, size_t n, Statistics* out);

/// Appends [opcode][u64 length][body] to `out`.
void AppendRecord(Op op, const std::string& body, std::string* out);

}  // namespace p2i::recording::mcap
