/// @file mcap_reader.cc
/// @brief MCAP reader: summary section via the footer, or recovery by scanning chunks.
#include "recording/mcap_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "recording/compression.h"

namespace p2i::recording {

using mcap::Decoder;
using mcap::Op;

namespace {

constexpr size_t kRecordHead = 9;                  // opcode + u64 length
constexpr size_t kFooterRecord = kRecordHead + 20;  // summary_start, summary_offset_start, crc
constexpr uint64_t kMaxRecord = 1ull << 34;        // 16 GiB: anything larger is corruption
constexpr uint64_t kMaxChunk = 1ull << 30;         // uncompressed chunk bound (writer: MiBs)

std::string OpName(uint8_t op) {
  switch (static_cast<Op>(op)) {
    case Op::kHeader: return "Header";
    case Op::kFooter: return "Footer";
    case Op::kSchema: return "Schema";
    case Op::kChannel: return "Channel";
    case Op::kMessage: return "Message";
    case Op::kChunk: return "Chunk";
    case Op::kMessageIndex: return "MessageIndex";
    case Op::kChunkIndex: return "ChunkIndex";
    case Op::kAttachment: return "Attachment";
    case Op::kAttachmentIndex: return "AttachmentIndex";
    case Op::kStatistics: return "Statistics";
    case Op::kMetadata: return "Metadata";
    case Op::kMetadataIndex: return "MetadataIndex";
    case Op::kSummaryOffset: return "SummaryOffset";
    case Op::kDataEnd: return "DataEnd";
  }
  return "opcode 0x" + std::to_string(op);
}

}  // namespace

McapReader::~McapReader() {
  if (file_) std::fclose(file_);
}

bool McapReader::ReadAt(uint64_t offset, size_t n, std::string* out) {
  out->resize(n);
  if (n == 0) return true;
  if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) return false;
  return std::fread(out->data(), 1, n, file_) == n;
}

bool McapReader::Open(const std::string& path, std::string* error) {
  path_ = path;
  summary_ = McapSummary();
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) {
    *error = "cannot open " + path + ": " + std::strerror(errno);
    return false;
  }
  struct stat st {};
  fstat(fileno(file_), &st);
  summary_.file_size = static_cast<uint64_t>(st.st_size);
  std::string head;
  if (summary_.file_size < 8 + kRecordHead || !ReadAt(0, 8 + kRecordHead, &head) ||
      std::memcmp(head.data(), mcap::kMagic, 8) != 0) {
    *error = path + " is not an MCAP file (no leading magic \\x89MCAP0\\r\\n)";
    return false;
  }
  Decoder d(reinterpret_cast<const uint8_t*>(head.data()) + 8, kRecordHead);
  const uint8_t op = d.U8();
  const uint64_t len = d.U64();
  if (op != static_cast<uint8_t>(Op::kHeader) || len > summary_.file_size) {
    *error = path + ": the first record is not a Header (malformed MCAP file)";
    return false;
  }
  if (!ReadAt(8 + kRecordHead, static_cast<size_t>(len), &buf_)) {
    *error = path + ": truncated Header record";
    return false;
  }
  Decoder h(reinterpret_cast<const uint8_t*>(buf_.data()), buf_.size());
  summary_.profile = h.Str();
  summary_.library = h.Str();
  data_start_ = 8 + kRecordHead + len;
  std::string ignored;
  if (ReadSummarySection(&ignored)) return true;
  // No (valid) summary: a recorder killed mid-run, or a writer that wrote none. Scan.
  McapSummary scanned = summary_;
  scanned.has_summary = false;
  if (!Scan(nullptr, &scanned, error)) return false;
  summary_ = std::move(scanned);
  return true;
}

bool McapReader::ReadSummarySection(std::string* error) {
  const uint64_t size = summary_.file_size;
  if (size < data_start_ + kFooterRecord + 8) return false;
  std::string tail;
  if (!ReadAt(size - 8 - kFooterRecord, kFooterRecord + 8, &tail)) return false;
  if (std::memcmp(tail.data() + kFooterRecord, mcap::kMagic, 8) != 0) return false;
  Decoder f(reinterpret_cast<const uint8_t*>(tail.data()), kFooterRecord);
  if (f.U8() != static_cast<uint8_t>(Op::kFooter) || f.U64() != 20) return false;
  summary_.has_footer = true;
  const uint64_t summary_start = f.U64();
  const uint64_t summary_offset_start = f.U64();
  const uint32_t crc = f.U32();
  const uint64_t footer_at = size - 8 - kFooterRecord;
  if (summary_start == 0 || summary_start < data_start_ || summary_start > footer_at) return false;
  if (!ReadAt(summary_start, static_cast<size_t>(footer_at - summary_start), &buf_)) return false;
  if (crc != 0) {
    uint32_t c = Crc32(0, buf_.data(), buf_.size());
    c = Crc32(c, tail.data(), 1 + 8 + 16);
    if (c != crc) {
      *error = "summary CRC mismatch";
      return false;
    }
  }
  const uint64_t end = summary_offset_start ? summary_offset_start : footer_at;
  if (end < summary_start || end > footer_at) return false;
  McapSummary s = summary_;
  Decoder d(reinterpret_cast<const uint8_t*>(buf_.data()), static_cast<size_t>(end - summary_start));
  bool has_stats = false;
  while (d.ok() && d.Remaining() > 0) {
    const uint8_t op = d.U8();
    const uint64_t len = d.U64();
    if (!d.ok() || len > d.Remaining()) return false;
    const uint8_t* body = d.Take(static_cast<size_t>(len));
    switch (static_cast<Op>(op)) {
      case Op::kSchema: {
        mcap::Schema x;
        if (mcap::DecodeSchema(body, len, &x)) s.schemas[x.id] = std::move(x);
        break;
      }
      case Op::kChannel: {
        mcap::Channel x;
        if (!mcap::DecodeChannel(body, len, &x)) return false;
        s.channels[x.id] = std::move(x);
        break;
      }
      case Op::kChunkIndex: {
        mcap::ChunkIndex x;
        if (!mcap::DecodeChunkIndex(body, len, &x)) return false;
        s.compressed_bytes += x.compressed_size;
        s.uncompressed_bytes += x.uncompressed_size;
        ++s.chunks_by_compression[x.compression];
        break;
      }
      case Op::kStatistics:
        if (!mcap::DecodeStatistics(body, len, &s.stats)) return false;
        has_stats = true;
        break;
      default:
        break;  // attachment / metadata indexes: not used by p2i
    }
  }
  if (!d.ok() || !has_stats) return false;  // p2i needs the statistics; else scan
  s.has_summary = true;
  s.readable_bytes = summary_start;
  summary_ = std::move(s);
  return true;
}

bool McapReader::HandleRecord(uint8_t op, const uint8_t* body, size_t n, const MessageFn* fn,
                              McapSummary* into, bool* stop) {
  switch (static_cast<Op>(op)) {
    case Op::kSchema: {
      mcap::Schema x;
      if (mcap::DecodeSchema(body, n, &x)) into->schemas[x.id] = std::move(x);
      return true;
    }
    case Op::kChannel: {
      mcap::Channel x;
      if (!mcap::DecodeChannel(body, n, &x)) return false;
      into->channels[x.id] = std::move(x);
      return true;
    }
    case Op::kMessage: {
      mcap::Message m;
      if (!mcap::DecodeMessage(body, n, &m)) return false;
      const auto ch = into->channels.find(m.channel_id);
      if (ch == into->channels.end()) return false;  // message before its channel: malformed
      if (fn) {
        if (!(*fn)(ch->second, m)) *stop = true;
        return true;
      }
      auto& st = into->stats;
      if (st.message_count == 0 || m.log_time < st.message_start_time)
        st.message_start_time = m.log_time;
      if (m.log_time > st.message_end_time) st.message_end_time = m.log_time;
      ++st.message_count;
      ++st.channel_message_counts[m.channel_id];
      return true;
    }
    default:
      return true;  // other records inside the data section are skipped
  }
}

std::string McapReader::ScanChunk(const uint8_t* body, size_t len, uint64_t at,
                                  const MessageFn* fn, McapSummary* into, bool* stop) {
  Decoder c(body, len);
  c.U64();
  c.U64();
  const uint64_t usize = c.U64();
  const uint32_t crc = c.U32();
  const std::string compression = c.Str();
  const uint64_t csize = c.U64();
  const uint8_t* records = c.ok() ? c.Take(static_cast<size_t>(csize)) : nullptr;
  std::string why;
  if (!records || usize > kMaxChunk) return "malformed Chunk record at byte " + std::to_string(at);
  if (!Decompress(compression, records, static_cast<size_t>(csize), static_cast<size_t>(usize),
                  &chunk_, &why)) {
    return "corrupt Chunk at byte " + std::to_string(at) + ": " + why;
  }
  if (crc != 0 && Crc32(0, chunk_.data(), chunk_.size()) != crc) {
    return "Chunk at byte " + std::to_string(at) + " fails its CRC (corrupt)";
  }
  if (!fn) {
    into->compressed_bytes += csize;
    into->uncompressed_bytes += usize;
    ++into->chunks_by_compression[compression];
    ++into->stats.chunk_count;
  }
  Decoder r(reinterpret_cast<const uint8_t*>(chunk_.data()), chunk_.size());
  while (r.ok() && r.Remaining() > 0 && !*stop) {
    const uint8_t rop = r.U8();
    const uint64_t rlen = r.U64();
    const uint8_t* rb =
        r.ok() && rlen <= r.Remaining() ? r.Take(static_cast<size_t>(rlen)) : nullptr;
    if (!rb || !HandleRecord(rop, rb, static_cast<size_t>(rlen), fn, into, stop)) {
      return "malformed record inside the Chunk at byte " + std::to_string(at);
    }
  }
  return "";
}

bool McapReader::Scan(const MessageFn* fn, McapSummary* into, std::string* error) {
  const uint64_t size = into->file_size;
  uint64_t at = data_start_;
  into->stop_reason.clear();
  auto stop_at = [&](const std::string& why) {
    into->readable_bytes = at;
    into->stop_reason = why;
  };
  std::string head;
  while (true) {
    if (at + kRecordHead > size) {
      stop_at(at == size ? "end of file without DataEnd (the writer did not finish)"
                         : "truncated record header at byte " + std::to_string(at));
      return true;
    }
    if (!ReadAt(at, kRecordHead, &head)) {
      *error = "reading " + path_ + " at byte " + std::to_string(at) + " failed";
      return false;
    }
    Decoder hd(reinterpret_cast<const uint8_t*>(head.data()), kRecordHead);
    const uint8_t op = hd.U8();
    const uint64_t len = hd.U64();
    if (op == 0 || len > kMaxRecord) {
      stop_at("malformed record (opcode " + std::to_string(op) + ", length " +
              std::to_string(len) + ") at byte " + std::to_string(at));
      return true;
    }
    if (at + kRecordHead + len > size) {
      stop_at("truncated " + OpName(op) + " record at byte " + std::to_string(at) + " (" +
              std::to_string(size - at - kRecordHead) + " of " + std::to_string(len) +
              " bytes present)");
      return true;
    }
    if (op == static_cast<uint8_t>(Op::kDataEnd)) {
      stop_at("");
      return true;
    }
    const bool wanted = op == static_cast<uint8_t>(Op::kChunk) ||
                        op == static_cast<uint8_t>(Op::kSchema) ||
                        op == static_cast<uint8_t>(Op::kChannel) ||
                        op == static_cast<uint8_t>(Op::kMessage);
    if (wanted) {
      if (!ReadAt(at + kRecordHead, static_cast<size_t>(len), &buf_)) {
        *error = "reading " + path_ + " at byte " + std::to_string(at) + " failed";
        return false;
      }
      const auto* body = reinterpret_cast<const uint8_t*>(buf_.data());
      bool stop = false;
      if (op == static_cast<uint8_t>(Op::kChunk)) {
        const std::string why = ScanChunk(body, static_cast<size_t>(len), at, fn, into, &stop);
        if (!why.empty()) {
          stop_at(why);
          return true;
        }
      } else if (!HandleRecord(op, body, static_cast<size_t>(len), fn, into, &stop)) {
        stop_at("malformed " + OpName(op) + " record at byte " + std::to_string(at));
        return true;
      }
      if (stop) return true;
    }
    at += kRecordHead + len;
  }
}

bool McapReader::ReadMessages(const MessageFn& fn, std::string* error) {
  if (!file_) {
    *error = "McapReader::ReadMessages before a successful Open";
    return false;
  }
  McapSummary scratch;
  scratch.file_size = summary_.file_size;
  const bool ok = Scan(&fn, &scratch, error);
  if (!summary_.has_summary) summary_.stop_reason = scratch.stop_reason;
  return ok;
}

}  // namespace p2i::recording
