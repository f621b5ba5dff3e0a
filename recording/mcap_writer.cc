/// @file mcap_writer.cc
/// @brief MCAP writer: chunks with CRC and compression, message indexes, summary, footer.
#include "recording/mcap_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "recording/compression.h"

namespace p2i::recording {

using mcap::Encoder;
using mcap::Op;

void McapWriterOptions::Validate() const {
  if (!IsSupportedCompression(compression)) {
    throw std::invalid_argument("McapWriterOptions.compression: '" + compression +
                                "' is not supported (use zstd, lz4 or \"\")");
  }
  if (chunk_size < 1024) {
    throw std::invalid_argument("McapWriterOptions.chunk_size: " + std::to_string(chunk_size) +
                                " bytes is too small (>= 1024)");
  }
  if (!(chunk_max_age_s > 0)) {
    throw std::invalid_argument("McapWriterOptions.chunk_max_age_s: must be > 0 s");
  }
  if (compression == "zstd" && (compression_level < -5 || compression_level > 22)) {
    throw std::invalid_argument("McapWriterOptions.compression_level: zstd takes -5..22");
  }
}

McapWriter::~McapWriter() {
  try {
    if (IsOpen()) Close();
  } catch (...) {
  }
}

void McapWriter::Open(const std::string& path, const McapWriterOptions& options) {
  options.Validate();
  options_ = options;
  path_ = path;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw std::runtime_error("cannot create " + path + ": " + std::strerror(errno) +
                             " (check the folder exists and is writable)");
  }
  std::string head(reinterpret_cast<const char*>(mcap::kMagic), 8);
  std::string body;
  Encoder e(&body);
  e.Str(options_.profile);
  e.Str(options_.library);
  mcap::AppendRecord(Op::kHeader, body, &head);
  WriteOut(head);
  data_crc_ = Crc32(0, head.data(), head.size());  // DataEnd's CRC covers the file from byte 0
  chunk_opened_ = std::chrono::steady_clock::now();
}

void McapWriter::WriteOut(const std::string& bytes) {
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("writing " + path_ + " failed: " + std::strerror(errno) +
                               " (disk full?)");
    }
    done += static_cast<size_t>(n);
  }
  offset_ += bytes.size();
}

uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding,
                               const std::string& data) {
  mcap::Schema s{static_cast<uint16_t>(schemas_.size() + 1), name, encoding, data};
  mcap::AppendRecord(Op::kSchema, mcap::EncodeSchema(s), &chunk_);
  schemas_.push_back(std::move(s));
  return schemas_.back().id;
}

uint16_t McapWriter::AddChannel(uint16_t schema_id, const std::string& topic,
                                const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  mcap::Channel c{static_cast<uint16_t>(channels_.size() + 1), schema_id, topic,
                  message_encoding, metadata};
  mcap::AppendRecord(Op::kChannel, mcap::EncodeChannel(c), &chunk_);
  channels_.push_back(std::move(c));
  return channels_.back().id;
}

void McapWriter::Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                       uint64_t publish_time, size_t size,
                       const std::function<void(uint8_t*)>& fill) {
  if (!IsOpen()) throw std::logic_error("McapWriter::Write before Open");
  if (!chunk_has_messages_) {
    chunk_start_ = chunk_end_ = log_time;
    chunk_opened_ = std::chrono::steady_clock::now();
  }
  chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
  Encoder e(&chunk_);
  e.U8(static_cast<uint8_t>(Op::kMessage));
  e.U64(2 + 4 + 8 + 8 + size);
  e.U16(channel_id);
  e.U32(sequence);
  e.U64(log_time);
  e.U64(publish_time);
  const size_t at = chunk_.size();
  chunk_.resize(at + size);
  fill(reinterpret_cast<uint8_t*>(chunk_.data() + at));
  chunk_has_messages_ = true;
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  if (stats_.message_count == 0 || log_time < stats_.message_start_time)
    stats_.message_start_time = log_time;
  stats_.message_end_time = std::max(stats_.message_end_time, log_time);
  ++stats_.message_count;
  ++stats_.channel_message_counts[channel_id];
  if (chunk_.size() >= options_.chunk_size) FlushChunk();
}

void McapWriter::Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time,
                       uint64_t publish_time, const void* data, size_t size) {
  Write(channel_id, sequence, log_time, publish_time, size,
        [&](uint8_t* dst) { std::memcpy(dst, data, size); });
}

void McapWriter::FlushIfDue() {
  if (!chunk_has_messages_) return;
  if (std::chrono::steady_clock::now() - chunk_opened_ >=
      std::chrono::duration<double>(options_.chunk_max_age_s))
    FlushChunk();
}

void McapWriter::FlushChunk() {
  if (!IsOpen() || chunk_.empty()) return;
  Compress(options_.compression, options_.compression_level,
           reinterpret_cast<const uint8_t*>(chunk_.data()), chunk_.size(), &compressed_);
  mcap::ChunkIndex ci;
  ci.message_start_time = chunk_has_messages_ ? chunk_start_ : 0;
  ci.message_end_time = chunk_has_messages_ ? chunk_end_ : 0;
  ci.chunk_start_offset = offset_;
  ci.compression = options_.compression;
  ci.compressed_size = compressed_.size();
  ci.uncompressed_size = chunk_.size();

  std::string out;
  out.reserve(compressed_.size() + 256);
  Encoder e(&out);
  const size_t body = 8 + 8 + 8 + 4 + 4 + ci.compression.size() + 8 + compressed_.size();
  e.U8(static_cast<uint8_t>(Op::kChunk));
  e.U64(body);
  e.U64(ci.message_start_time);
  e.U64(ci.message_end_time);
  e.U64(chunk_.size());
  e.U32(Crc32(0, chunk_.data(), chunk_.size()));
  e.Str(ci.compression);
  e.U64(compressed_.size());
  out.append(compressed_);
  ci.chunk_length = out.size();
  // Message indexes, one per channel with messages in this chunk.
  const uint64_t index_start = offset_ + out.size();
  for (const auto& [channel, entries] : chunk_index_) {
    ci.message_index_offsets[channel] = offset_ + out.size();
    std::string b;
    Encoder m(&b);
    m.U16(channel);
    m.U32(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [t, off] : entries) {
      m.U64(t);
      m.U64(off);
    }
    mcap::AppendRecord(Op::kMessageIndex, b, &out);
  }
  ci.message_index_length = offset_ + out.size() - index_start;
  data_crc_ = Crc32(data_crc_, out.data(), out.size());
  WriteOut(out);
  if (options_.fsync_chunks) ::fsync(fd_);
  chunk_indexes_.push_back(std::move(ci));
  ++stats_.chunk_count;
  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
  chunk_opened_ = std::chrono::steady_clock::now();
}

void McapWriter::Close() {
  if (!IsOpen()) return;
  FlushChunk();
  WriteSummaryAndFooter();
  if (options_.fsync_chunks) ::fsync(fd_);
  ::close(fd_);
  fd_ = -1;
}

void McapWriter::WriteSummaryAndFooter() {
  std::string out;
  {
    std::string body;
    Encoder e(&body);
    e.U32(data_crc_);
    mcap::AppendRecord(Op::kDataEnd, body, &out);
  }
  const uint64_t summary_start = offset_ + out.size();
  struct Group {
    Op op;
    uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](Op op, const std::vector<std::string>& bodies) {
    if (bodies.empty()) return;
    const uint64_t start = offset_ + out.size();
    for (const auto& b : bodies) mcap::AppendRecord(op, b, &out);
    groups.push_back({op, start, offset_ + out.size() - start});
  };
  std::vector<std::string> bodies;
  for (const auto& s : schemas_) bodies.push_back(mcap::EncodeSchema(s));
  group(Op::kSchema, bodies);
  bodies.clear();
  for (const auto& c : channels_) bodies.push_back(mcap::EncodeChannel(c));
  group(Op::kChannel, bodies);
  bodies.clear();
  for (const auto& ci : chunk_indexes_) bodies.push_back(mcap::EncodeChunkIndex(ci));
  group(Op::kChunkIndex, bodies);
  stats_.schema_count = static_cast<uint16_t>(schemas_.size());
  stats_.channel_count = static_cast<uint32_t>(channels_.size());
  group(Op::kStatistics, {mcap::EncodeStatistics(stats_)});
  const uint64_t summary_offset_start = offset_ + out.size();
  for (const auto& g : groups) {
    std::string b;
    Encoder e(&b);
    e.U8(static_cast<uint8_t>(g.op));
    e.U64(g.start);
    e.U64(g.length);
    mcap::AppendRecord(Op::kSummaryOffset, b, &out);
  }
  // Footer: the CRC covers the summary section through footer.summary_offset_start.
  const size_t summary_at = static_cast<size_t>(summary_start - offset_);
  std::string footer;
  Encoder f(&footer);
  f.U8(static_cast<uint8_t>(Op::kFooter));
  f.U64(8 + 8 + 4);
  f.U64(summary_start);
  f.U64(summary_offset_start);
  uint32_t crc = Crc32(0, out.data() + summary_at, out.size() - summary_at);
  crc = Crc32(crc, footer.data(), footer.size());
  f.U32(crc);
  out.append(footer);
  out.append(reinterpret_cast<const char*>(mcap::kMagic), 8);
  WriteOut(out);
}

}  // namespace p2i::recording
