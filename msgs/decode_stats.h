/// @file decode_stats.h
/// @brief Process-wide counters of rejected messages, keyed by the reason class.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <string>

namespace p2i::msgs {

/// Why a decoder rejected a message. The name (DecodeReasonName) prefixes every error string.
enum class DecodeReason : int {
  kOk = 0,
  kOversized,         ///< whole message or header frame above the size limit
  kUnparsable,        ///< header frame is not a valid protobuf of the expected message
  kUnknownType,       ///< header.type is 0 or not in MsgType
  kBadVersion,        ///< header.schema_version outside the supported range
  kTypeMismatch,      ///< header.type is valid but not the type asked for
  kMissingBlob,       ///< fewer blob frames than referenced, or a null blob
  kExtraBlob,         ///< blob frames nobody references
  kBlobSize,          ///< blob byte count != height * step
  kBadImage,          ///< encoding, width/height (0 or > 16384), step, scale, blob index
  kNonFinite,         ///< NaN or infinity in a numeric field
  kBadQuaternion,     ///< missing orientation or norm off by more than 1e-3
  kBadValue,          ///< other out-of-range field (matrix sizes, counts, coverage, ...)
  kInternal,          ///< an exception inside the decoder (e.g. out of memory)
  kCount
};

const char* DecodeReasonName(DecodeReason reason);

/// Counters of decoded and rejected messages. All methods are thread-safe (relaxed atomics):
/// every Decode() call in the process reports here.
class DecodeStats {
 public:
  static DecodeStats& Global();

  void Count(DecodeReason reason) {
    counts_[static_cast<int>(reason)].fetch_add(1, std::memory_order_relaxed);
  }
  uint64_t Get(DecodeReason reason) const {
    return counts_[static_cast<int>(reason)].load(std::memory_order_relaxed);
  }
  /// Sum of all rejection counters (everything but kOk).
  uint64_t Rejected() const;
  /// Reason name -> count, for every reason including "ok" (decoded successfully).
  std::map<std::string, uint64_t> Snapshot() const;
  void Reset();

 private:
  std::array<std::atomic<uint64_t>, static_cast<int>(DecodeReason::kCount)> counts_{};
};

}  // namespace p2i::msgs
