/// @file mcap_format.cc
/// @brief MCAP field encoding and the bodies of Schema, Channel, Message, ChunkIndex and
/// Statistics records.
#include "recording/mcap_format.h"

namespace p2i::recording::mcap {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the MCAP encoder copies integers as host bytes: little-endian hosts only");

void Encoder::StrMap(const std::map<std::string, std::string>& m) {
  size_t bytes = 0;
  for (const auto& [k, v] : m) bytes += 8 + k.size() + v.size();
  U32(static_cast<uint32_t>(bytes));
  for (const auto& [k, v] : m) {
    Str(k);
    Str(v);
  }
}

void Encoder::U16U64Map(const std::map<uint16_t, uint64_t>& m) {
  U32(static_cast<uint32_t>(m.size() * 10));
  for (const auto& [k, v] : m) {
    U16(k);
    U64(v);
  }
}

template <typename T>
T Decoder::Fixed() {
  T v{};
  if (!ok_ || Remaining() < sizeof(T)) {
    ok_ = false;
    return v;
  }
  std::memcpy(&v, p_, sizeof(T));
  p_ += sizeof(T);
  return v;
}

uint8_t Decoder::U8() { return Fixed<uint8_t>(); }
uint16_t Decoder::U16() { return Fixed<uint16_t>(); }
uint32_t Decoder::U32() { return Fixed<uint32_t>(); }
uint64_t Decoder::U64() { return Fixed<uint64_t>(); }

const uint8_t* Decoder::Take(size_t n) {
  if (!ok_ || Remaining() < n) {
    ok_ = false;
    return nullptr;
  }
  const uint8_t* p = p_;
  p_ += n;
  return p;
}

std::string Decoder::Str() {
  const uint32_t n = U32();
  const uint8_t* p = Take(n);
  return p ? std::string(reinterpret_cast<const char*>(p), n) : std::string();
}

std::map<std::string, std::string> Decoder::StrMap() {
  std::map<std::string, std::string> m;
  const uint32_t bytes = U32();
  const uint8_t* p = Take(bytes);
  if (!p) return m;
  Decoder inner(p, bytes);
  while (inner.ok() && inner.Remaining() > 0) {
    std::string k = inner.Str();
    std::string v = inner.Str();
    if (inner.ok()) m[k] = v;
  }
  if (!inner.ok()) ok_ = false;
  return m;
}

std::map<uint16_t, uint64_t> Decoder::U16U64Map() {
  std::map<uint16_t, uint64_t> m;
  const uint32_t bytes = U32();
  const uint8_t* p = Take(bytes);
  if (!p) return m;
  Decoder inner(p, bytes);
  while (inner.ok() && inner.Remaining() > 0) {
    const uint16_t k = inner.U16();
    const uint64_t v = inner.U64();
    if (inner.ok()) m[k] = v;
  }
  if (!inner.ok()) ok_ = false;
  return m;
}

std::string EncodeSchema(const Schema& s) {
  std::string b;
  Encoder e(&b);
  e.U16(s.id);
  e.Str(s.name);
  e.Str(s.encoding);
  e.Str(s.data);  // uint32 length-prefixed bytes
  return b;
}

std::string EncodeChannel(const Channel& c) {
  std::string b;
  Encoder e(&b);
  e.U16(c.id);
  e.U16(c.schema_id);
  e.Str(c.topic);
  e.Str(c.message_encoding);
  e.StrMap(c.metadata);
  return b;
}

std::string EncodeChunkIndex(const ChunkIndex& c) {
  std::string b;
  Encoder e(&b);
  e.U64(c.message_start_time);
  e.U64(c.message_end_time);
  e.U64(c.chunk_start_offset);
  e.U64(c.chunk_length);
  e.U16U64Map(c.message_index_offsets);
  e.U64(c.message_index_length);
  e.Str(c.compression);
  e.U64(c.compressed_size);
  e.U64(c.uncompressed_size);
  return b;
}

std::string EncodeStatistics(const Statistics& s) {
  std::string b;
  Encoder e(&b);
  e.U64(s.message_count);
  e.U16(s.schema_count);
  e.U32(s.channel_count);
  e.U32(s.attachment_count);
  e.U32(s.metadata_count);
  e.U32(s.chunk_count);
  e.U64(s.message_start_time);
  e.U64(s.message_end_time);
  e.U16U64Map(s.channel_message_counts);
  return b;
}

bool DecodeSchema(const uint8_t* p, size_t n, Schema* out) {
  Decoder d(p, n);
  Schema s;
  s.id = d.U16();
  s.name = d.Str();
  s.encoding = d.Str();
  s.data = d.Str();
  if (!d.ok() || s.id == 0) return false;  // id 0 is invalid (spec: ignore it)
  *out = std::move(s);
  return true;
}

bool DecodeChannel(const uint8_t* p, size_t n, Channel* out) {
  Decoder d(p, n);
  Channel c;
  c.id = d.U16();
  c.schema_id = d.U16();
  c.topic = d.Str();
  c.message_encoding = d.Str();
  c.metadata = d.StrMap();
  if (!d.ok()) return false;
  *out = std::move(c);
  return true;
}

bool DecodeMessage(const uint8_t* p, size_t n, Message* out) {
  Decoder d(p, n);
  Message m;
  m.channel_id = d.U16();
  m.sequence = d.U32();
  m.log_time = d.U64();
  m.publish_time = d.U64();
  if (!d.ok()) return false;
  m.size = d.Remaining();
  m.data = d.Take(m.size);
  *out = m;
  return true;
}

bool DecodeChunkIndex(const uint8_t* p, size_t n, ChunkIndex* out) {
  Decoder d(p, n);
  ChunkIndex c;
  c.message_start_time = d.U64();
  c.message_end_time = d.U64();
  c.chunk_start_offset = d.U64();
  c.chunk_length = d.U64();
  c.message_index_offsets = d.U16U64Map();
  c.message_index_length = d.U64();
  c.compression = d.Str();
  c.compressed_size = d.U64();
  c.uncompressed_size = d.U64();
  if (!d.ok()) return false;
  *out = std::move(c);
  return true;
}

bool DecodeStatistics(const uint8_t* p, size_t n, Statistics* out) {
  Decoder d(p, n);
  Statistics s;
  s.message_count = d.U64();
  s.schema_count = d.U16();
  s.channel_count = d.U32();
  s.attachment_count = d.U32();
  s.metadata_count = d.U32();
  s.chunk_count = d.U32();
  s.message_start_time = d.U64();
  s.message_end_time = d.U64();
  s.channel_message_counts = d.U16U64Map();
  if (!d.ok()) return false;
  *out = std::move(s);
  return true;
}

void AppendRecord(Op op, const std::string& body, std::string* out) {
  Encoder e(out);
  e.U8(static_cast<uint8_t>(op));
  e.U64(body.size());
  out->append(body);
}

}  // namespace p2i::recording::mcap
