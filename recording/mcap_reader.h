/// @file mcap_reader.h
/// @brief Reads MCAP files: the summary section when the file has a valid one, otherwise a
/// linear scan of the data section that recovers everything up to the last complete chunk
/// (a recorder killed mid-write leaves a file without summary and footer).
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <string>

#include "recording/mcap_format.h"

namespace p2i::recording {

/// What a file holds, from its summary section or, without one, from scanning it.
struct McapSummary {
  std::string profile, library;  ///< Header record
  uint64_t file_size = 0;
  bool has_summary = false;      ///< read from a valid summary section (else: scanned)
  bool has_footer = false;       ///< footer + trailing magic present (file closed cleanly)
  std::map<uint16_t, mcap::Schema> schemas;
  std::map<uint16_t, mcap::Channel> channels;
  mcap::Statistics stats;        ///< from the Statistics record, or counted while scanning
  uint64_t compressed_bytes = 0, uncompressed_bytes = 0;  ///< of all chunk records
  std::map<std::string, uint32_t> chunks_by_compression;  ///< "zstd" -> 12, "" -> 1
  /// Scans only: where the readable data ends and why ("" = at DataEnd, i.e. complete), e.g.
  /// "truncated Chunk record at byte 123456 (8388608 of 9000000 bytes present)".
  uint64_t readable_bytes = 0;
  std::string stop_reason;
};

/// Reads one file. Not thread-safe (one owner thread); never crashes or reads out of bounds on
/// malformed input: bad records end the scan with a reason.
class McapReader {
 public:
  McapReader() = default;
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  /// Opens `path`, checks the magic and Header, reads the summary (or scans). False + error
  /// ("what, where, how to fix") if the file is unreadable or not MCAP at all.
  bool Open(const std::string& path, std::string* error);
  const McapSummary& Summary() const { return summary_; }

  /// Called for each message in file order (log-time order for files written by McapWriter);
  /// `data` is valid during the call only. Return false to stop.
  using MessageFn = std::function<bool(const mcap::Channel& channel, const mcap::Message& m)>;
  /// Reads every message of the data section, up to the first incomplete or corrupt record
  /// (whose reason is in Summary().stop_reason afterwards). False + error on I/O errors only.
  bool ReadMessages(const MessageFn& fn, std::string* error);

 private:
  bool ReadAt(uint64_t offset, size_t n, std::string* out);
  bool ReadSummarySection(std::string* error);
  /// Walks the data section from after the Header; `fn` may be null (summary building).
  bool Scan(const MessageFn* fn, McapSummary* into, std::string* error);
  /// Handles one Schema / Channel / Message record (top level or inside a chunk). Returns false
  /// when the record is malformed; sets *stop when `fn` asked to stop.
  bool HandleRecord(uint8_t op, const uint8_t* body, size_t n, const MessageFn* fn,
                    McapSummary* into, bool* stop);
  /// Decompresses the Chunk record `body` (at byte `at`), checks its CRC and handles the records
  /// inside. Returns "" when the scan may go on, else why it stops there (malformed, corrupt).
  std::string ScanChunk(const uint8_t* body, size_t len, uint64_t at, const MessageFn* fn,
                        McapSummary* into, bool* stop);

  std::string path_;
  FILE* file_ = nullptr;
  uint64_t data_start_ = 0;  // first record after the Header
  McapSummary summary_;
  std::string buf_, chunk_;  // reused buffers
};

}  // namespace p2i::recording
