/// @file checkpoint_tamper.h
/// @brief Damaged checkpoints for tests (torch-free: byte edits of the file): a torn file, random
/// bytes, an empty file, another format version, a tensor record cut short (the zip's size
/// fields of one record set to 16 bytes, as a bad copy or a torn record would leave it), NaN
/// weights (a record overwritten with NaN). The format-2 container header (docs/MODEL.md) is
/// re-written with a matching size and CRC-32 where the damage is meant to get past the checksum
/// (a saver bug, or a format-1 file, which has no checksum).
#pragma once

#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace p2i::testing {

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// A format-2 file split into its two header lines (with their '\n') and the zip payload.
struct CheckpointParts {
  std::string version_line, header_line, payload;
};

inline CheckpointParts SplitCheckpoint(const std::string& file) {
  const size_t a = file.find('\n');
  const size_t b = file.find('\n', a + 1);
  if (file.compare(0, 8, "P2ICKPT ") != 0 || a == std::string::npos || b == std::string::npos)
    throw std::runtime_error("not a format-2 checkpoint");
  return {file.substr(0, a + 1), file.substr(a + 1, b - a), file.substr(b + 1)};
}

/// Re-assembles a format-2 file whose header matches `payload` (size and CRC-32).
inline std::string JoinCheckpoint(const CheckpointParts& p) {
  char crc[16];
  std::snprintf(crc, sizeof(crc), "%08lx",
                crc32(0, reinterpret_cast<const Bytef*>(p.payload.data()),
                      static_cast<uInt>(p.payload.size())));
  std::string header = std::regex_replace(p.header_line, std::regex("\"payload_bytes\":[0-9]+"),
                                          "\"payload_bytes\":" + std::to_string(p.payload.size()));
  header = std::regex_replace(header, std::regex("\"payload_crc32\":\"[0-9a-f]+\""),
                              std::string("\"payload_crc32\":\"") + crc + "\"");
  return p.version_line + header + p.payload;
}

namespace tamper_detail {
inline uint32_t U32(const std::string& s, size_t at) {
  uint32_t v;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}
inline uint16_t U16(const std::string& s, size_t at) {
  uint16_t v;
  std::memcpy(&v, s.data() + at, 2);
  return v;
}
inline void SetU32(std::string* s, size_t at, uint32_t v) { std::memcpy(&(*s)[at], &v, 4); }

// Calls f(central_entry_offset, local_header_offset, name) for each zip entry.
template <class F>
void ForEachEntry(const std::string& zip, F f) {
  const size_t eocd = zip.rfind(std::string("PK\x05\x06", 4));
  if (eocd == std::string::npos) throw std::runtime_error("no zip end record");
  const uint16_t count = U16(zip, eocd + 10);
  size_t at = U32(zip, eocd + 16);
  for (uint16_t i = 0; i < count; ++i) {
    if (U32(zip, at) != 0x02014b50u) throw std::runtime_error("bad zip central entry");
    const uint16_t n = U16(zip, at + 28), e = U16(zip, at + 30), c = U16(zip, at + 32);
    f(at, static_cast<size_t>(U32(zip, at + 42)), zip.substr(at + 46, n));
    at += 46 + n + e + c;
  }
}
}  // namespace tamper_detail

/// The zip entry names of the tensor records (".../data/N"), in zip order.
inline std::vector<std::string> TensorRecords(const std::string& zip) {
  std::vector<std::string> found;
  tamper_detail::ForEachEntry(zip, [&](size_t, size_t, const std::string& name) {
    if (name.find("/data/") != std::string::npos) found.push_back(name);
  });
  if (found.empty()) throw std::runtime_error("no tensor record in the zip");
  return found;
}

/// Sets the recorded size of entry `name` to `bytes` (local header and central directory).
inline std::string CutRecord(std::string zip, const std::string& name, uint32_t bytes) {
  bool done = false;
  tamper_detail::ForEachEntry(zip, [&](size_t central, size_t local, const std::string& n) {
    if (n != name) return;
    done = true;
    if (tamper_detail::U32(zip, central + 24) <= bytes) return;  // already that short
    for (size_t off : {central + 20, central + 24}) tamper_detail::SetU32(&zip, off, bytes);
    for (size_t off : {local + 18, local + 22}) tamper_detail::SetU32(&zip, off, bytes);
    done = true;
  });
  if (!done) throw std::runtime_error("no zip entry " + name);
  return zip;
}

/// Overwrites the data of entry `name` with float NaN (the zip stores records uncompressed).
inline std::string PoisonRecord(std::string zip, const std::string& name) {
  bool done = false;
  tamper_detail::ForEachEntry(zip, [&](size_t central, size_t local, const std::string& n) {
    if (n != name) return;
    const uint32_t size = tamper_detail::U32(zip, central + 24);
    const size_t data = local + 30 + tamper_detail::U16(zip, local + 26) +
                        tamper_detail::U16(zip, local + 28);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t i = 0; i + 4 <= size; i += 4) std::memcpy(&zip[data + i], &nan, 4);
    done = true;
  });
  if (!done) throw std::runtime_error("no zip entry " + name);
  return zip;
}

/// The damaged variants of a good format-2 file, by name.
inline std::string Damaged(const std::string& good, const std::string& kind) {
  CheckpointParts p = SplitCheckpoint(good);
  if (kind == "empty") return "";
  if (kind == "torn") return good.substr(0, good.size() / 2);  // an interrupted write
  if (kind == "random") {
    std::mt19937 rng(7);
    std::string r(4096, '\0');
    for (auto& c : r) c = static_cast<char>(rng());
    return r;
  }
  if (kind == "version") return "P2ICKPT 99\n" + p.header_line + p.payload;
  if (kind == "flipped") {  // one bit of the payload, header untouched: the CRC catches it
    std::string f = good;
    f[f.size() - p.payload.size() / 2] ^= 0x10;
    return f;
  }
  // Which record a module's tensor lands in depends on LibTorch's pickling order (and a full
  // checkpoint holds tensors a reader skips, e.g. D's), so every tensor record is damaged.
  if (kind == "record" || kind == "record_v1") {  // records cut to 16 bytes
    for (const auto& r : TensorRecords(p.payload)) p.payload = CutRecord(p.payload, r, 16);
    return kind == "record" ? JoinCheckpoint(p)  // the header made to agree (a saver bug)
                            : p.payload;         // a format-1 file: bare zip, no checksum
  }
  if (kind == "nan") {  // NaN weights, the header made to agree
    for (const auto& r : TensorRecords(p.payload)) p.payload = PoisonRecord(p.payload, r);
    return JoinCheckpoint(p);
  }
  throw std::runtime_error("unknown damage " + kind);
}

}  // namespace p2i::testing
