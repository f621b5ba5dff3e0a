/// @file compression.h
/// @brief Chunk compression for MCAP: "zstd" (zstd frame), "lz4" (LZ4 frame format, as the
/// MCAP registry requires) or "" (none); CRC-32 (IEEE, zlib's) of record bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace p2i::recording {

/// True for "", "zstd" and "lz4".
bool IsSupportedCompression(const std::string& name);

/// Compresses `n` bytes into `out` (replaced). `level`: zstd level (1 = fast) or, for lz4,
/// its acceleration-free default when <= 0 and the HC level otherwise. Throws
/// std::runtime_error naming the library error on failure (out of memory).
void Compress(const std::string& name, int level, const uint8_t* data, size_t n,
              std::string* out);

/// Decompresses into `out` (resized to `uncompressed_size`). False + `error` when the data is
/// corrupt, of another size than announced, or the compression is unknown.
bool Decompress(const std::string& name, const uint8_t* data, size_t n, size_t uncompressed_size,
                std::string* out, std::string* error);

/// CRC-32 (ISO-HDLC / IEEE 802.3, as zlib and MCAP); `crc` continues a running value (0 to start).
uint32_t Crc32(uint32_t crc, const void* data, size_t n);

}  // namespace p2i::recording
