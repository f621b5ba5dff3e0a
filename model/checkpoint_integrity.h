/// @file checkpoint_integrity.h
/// @brief What LibTorch does not check in a checkpoint: the file container of format 2 (a
/// header line with the payload's size and CRC-32, then the LibTorch archive as the payload),
/// the tensor manifest written by the saver (element count of every parameter and buffer), and
/// checks of loaded tensors (storage holds the tensor, values finite). INTERNAL to model/.
///
/// File layout of format 2 (docs/MODEL.md):
///
///     P2ICKPT 2\n
///     {"payload_bytes": N, "payload_crc32": "1a2b3c4d", "tensors": {"G/fc.weight": 4096, ...}}\n
///     <N bytes: the torch::serialize::OutputArchive zip>
///
/// Format 1 files are the bare zip (they start with "PK"); they load without the checksum and
/// manifest checks (the tensor storage and finiteness checks still apply).
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include <torch/torch.h>

namespace p2i::model {

/// CRC-32 (IEEE 802.3, as zlib's crc32) of `size` bytes.
uint32_t Crc32(const void* data, size_t size, uint32_t crc = 0);

/// A checkpoint file read into memory and verified (format 2) or recognised as format 1.
struct CheckpointPayload {
  int container_version = 0;       ///< 2 = checked container, 1 = bare LibTorch zip
  std::string bytes;               ///< the LibTorch archive
  std::map<std::string, int64_t> manifest;  ///< "MODULE/name" -> numel (format 2 only)
};

/// Reads `path`; throws std::runtime_error naming the file and the reason for a missing,
/// empty, truncated, corrupted (CRC mismatch) or unknown file, and for a container version
/// other than 1 or `supported_version` ("format version N but this build reads version M").
CheckpointPayload ReadCheckpointPayload(const std::string& path, int supported_version);

/// The bytes of a format-2 file around `archive_bytes` (the manifest maps "MODULE/name" to
/// numel for every saved parameter and buffer).
std::string EncodeCheckpointFile(int version, const std::string& archive_bytes,
                                 const std::map<std::string, int64_t>& manifest);

/// Adds every parameter and buffer of `module` to `manifest` as "KEY/name" -> numel.
void AddToManifest(const std::string& key, torch::nn::Module& module,
                   std::map<std::string, int64_t>* manifest);

/// Loads `module` (recursively: parameters, buffers, children) from `archive`, saved under
/// `key` by torch::nn::Module::save, checking each tensor before it is copied into the module:
/// its storage holds all its elements (LibTorch 1.13 accepts a record shorter than its tensor
/// and reads past it), its shape is the module's, its element count is the manifest's (when the
/// manifest has entries) and every value is finite. Throws std::runtime_error naming the file,
/// the tensor and the reason; the module may then be partly loaded (callers discard it).
void LoadModuleChecked(torch::serialize::InputArchive& archive, const std::string& key,
                       torch::nn::Module& module, const std::string& path,
                       const std::map<std::string, int64_t>& manifest);

}  // namespace p2i::model
