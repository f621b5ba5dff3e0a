/// @file compression.cc
/// @brief zstd / LZ4 frame compression of MCAP chunks and zlib's CRC-32.
#include "recording/compression.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <stdexcept>

namespace p2i::recording {

bool IsSupportedCompression(const std::string& name) {
  return name.empty() || name == "zstd" || name == "lz4";
}

void Compress(const std::string& name, int level, const uint8_t* data, size_t n,
              std::string* out) {
  if (name.empty()) {
    out->assign(reinterpret_cast<const char*>(data), n);
    return;
  }
  if (name == "zstd") {
    out->resize(ZSTD_compressBound(n));
    const size_t r = ZSTD_compress(out->data(), out->size(), data, n, level);
    if (ZSTD_isError(r)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(r));
    out->resize(r);
    return;
  }
  if (name == "lz4") {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentSize = n;
    prefs.compressionLevel = level > 0 ? level : 0;
    out->resize(LZ4F_compressFrameBound(n, &prefs));
    const size_t r = LZ4F_compressFrame(out->data(), out->size(), data, n, &prefs);
    if (LZ4F_isError(r)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(r));
    out->resize(r);
    return;
  }
  throw std::runtime_error("unknown compression '" + name + "' (use zstd, lz4 or none)");
}

bool Decompress(const std::string& name, const uint8_t* data, size_t n, size_t uncompressed_size,
                std::string* out, std::string* error) {
  if (name.empty()) {
    if (n != uncompressed_size) {
      *error = "uncompressed chunk of " + std::to_string(n) + " bytes announces " +
               std::to_string(uncompressed_size);
      return false;
    }
    out->assign(reinterpret_cast<const char*>(data), n);
    return true;
  }
  if (name == "zstd") {
    // Check the frame's own size field before allocating (a corrupt chunk header must not
    // make us allocate gigabytes).
    const unsigned long long framed = ZSTD_getFrameContentSize(data, n);
    if (framed != ZSTD_CONTENTSIZE_UNKNOWN && framed != uncompressed_size) {
      *error = "zstd: the frame holds " + std::to_string(framed) + " bytes, the chunk announces " +
               std::to_string(uncompressed_size);
      return false;
    }
    out->resize(uncompressed_size);
    const size_t r = ZSTD_decompress(out->data(), out->size(), data, n);
    if (ZSTD_isError(r) || r != uncompressed_size) {
      *error = std::string("zstd: ") +
               (ZSTD_isError(r) ? ZSTD_getErrorName(r) : "size differs from the chunk header");
      return false;
    }
    return true;
  }
  if (name == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) {
      *error = "lz4: cannot create a decompression context";
      return false;
    }
    LZ4F_frameInfo_t info{};
    size_t header_len = n;
    if (LZ4F_isError(LZ4F_getFrameInfo(ctx, &info, data, &header_len)) ||
        (info.contentSize != 0 && info.contentSize != uncompressed_size)) {
      LZ4F_freeDecompressionContext(ctx);
      *error = "lz4: bad frame header or its size differs from the chunk's";
      return false;
    }
    out->resize(uncompressed_size);
    data += header_len;
    n -= header_len;
    size_t in_pos = 0, out_pos = 0, r = 1;
    while (r != 0 && in_pos < n) {
      size_t in_len = n - in_pos, out_len = uncompressed_size - out_pos;
      r = LZ4F_decompress(ctx, out->data() + out_pos, &out_len, data + in_pos, &in_len, nullptr);
      if (LZ4F_isError(r)) break;
      in_pos += in_len;
      out_pos += out_len;
      if (in_len == 0 && out_len == 0) break;  // no progress: output full or input exhausted
    }
    LZ4F_freeDecompressionContext(ctx);
    if (LZ4F_isError(r) || r != 0 || out_pos != uncompressed_size) {
      *error = std::string("lz4: ") +
               (LZ4F_isError(r) ? LZ4F_getErrorName(r) : "truncated frame or size differs");
      return false;
    }
    return true;
  }
  *error = "unknown compression '" + name + "'";
  return false;
}

uint32_t Crc32(uint32_t crc, const void* data, size_t n) {
  const auto* p = static_cast<const Bytef*>(data);
  while (n > 0) {  // zlib takes uInt lengths
    const uInt step = static_cast<uInt>(std::min<size_t>(n, 1u << 30));
    crc = static_cast<uint32_t>(crc32(crc, p, step));
    p += step;
    n -= step;
  }
  return crc;
}

}  // namespace p2i::recording
