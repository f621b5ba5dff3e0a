/// @file mcap_writer.h
/// @brief Writes MCAP files: chunked, compressed (zstd / lz4), message indexes after each
/// chunk, and on Close() a summary (schemas, channels, chunk indexes, statistics, summary
/// offsets) and the footer.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "recording/mcap_format.h"

namespace p2i::recording {

struct McapWriterOptions {
  std::string compression = "zstd";  ///< "zstd", "lz4" or "" (none)
  int compression_level = 1;         ///< zstd level (1 = fastest); lz4: 0 = fast, > 0 = HC level
  /// A chunk is compressed and written once its uncompressed records reach this size...
  size_t chunk_size = 4u << 20;
  /// ...or (FlushIfDue) once its first message is this old, so a kill loses at most this much.
  double chunk_max_age_s = 1.0;
  bool fsync_chunks = false;         ///< fsync after every chunk (power loss; a kill needs none)
  std::string profile;               ///< Header.profile ("" = none; p2i is not a ROS profile)
  std::string library = "p2i";
  /// Throws std::invalid_argument naming the field and the allowed values.
  void Validate() const;
};

/// One writer per file; not thread-safe (one owner thread).
///
/// Schema and Channel records go into the chunk being filled (before their first message), so
/// every complete chunk on disk is decodable on its own terms: a writer killed at any moment
/// leaves a file whose complete chunks McapReader recovers without the summary.
class McapWriter {
 public:
  McapWriter() = default;
  ~McapWriter();  ///< Close()s if still open (errors are swallowed: call Close() to see them)
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Creates/truncates `path` and writes magic + Header. Throws std::runtime_error naming the
  /// file and errno text.
  void Open(const std::string& path, const McapWriterOptions& options = {});
  bool IsOpen() const { return fd_ >= 0; }

  /// Ids start at 1 and are never reused.
  uint16_t AddSchema(const std::string& name, const std::string& encoding,
                     const std::string& data);
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic,
                      const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata = {});

  /// Appends a message of `size` bytes; `fill(dst)` writes exactly `size` bytes at dst (so big
  /// messages are serialized straight into the chunk buffer).
  void Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
             size_t size, const std::function<void(uint8_t* dst)>& fill);
  void Write(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
             const void* data, size_t size);

  /// Writes the current chunk if it is older than chunk_max_age_s (call it from the loop).
  void FlushIfDue();
  /// Compresses and writes the current chunk and its message indexes now.
  void FlushChunk();
  /// Last chunk, DataEnd, summary, summary offsets, footer, magic; closes the file.
  void Close();

  uint64_t MessageCount() const { return stats_.message_count; }
  uint64_t BytesWritten() const { return offset_; }
  uint32_t ChunkCount() const { return stats_.chunk_count; }

 private:
  void WriteOut(const std::string& bytes);
  void WriteSummaryAndFooter();

  McapWriterOptions options_;
  std::string path_;
  int fd_ = -1;
  uint64_t offset_ = 0;     // bytes written so far
  uint32_t data_crc_ = 0;   // running CRC of everything before DataEnd
  std::vector<mcap::Schema> schemas_;
  std::vector<mcap::Channel> channels_;
  std::vector<mcap::ChunkIndex> chunk_indexes_;
  mcap::Statistics stats_;
  // the chunk being filled
  std::string chunk_;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  // ch -> (t, off)
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_has_messages_ = false;
  std::chrono::steady_clock::time_point chunk_opened_;
  std::string compressed_;  // reused buffer
};

}  // namespace p2i::recording
