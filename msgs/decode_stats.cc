/// @file decode_stats.cc
/// @brief Process-wide rejection counters.
#include "msgs/decode_stats.h"

namespace p2i::msgs {

const char* DecodeReasonName(DecodeReason reason) {
  switch (reason) {
    case DecodeReason::kOk: return "ok";
    case DecodeReason::kOversized: return "oversized";
    case DecodeReason::kUnparsable: return "unparsable";
    case DecodeReason::kUnknownType: return "unknown_type";
    case DecodeReason::kBadVersion: return "bad_version";
    case DecodeReason::kTypeMismatch: return "type_mismatch";
    case DecodeReason::kMissingBlob: return "missing_blob";
    case DecodeReason::kExtraBlob: return "extra_blob";
    case DecodeReason::kBlobSize: return "blob_size";
    case DecodeReason::kBadImage: return "bad_image";
    case DecodeReason::kNonFinite: return "non_finite";
    case DecodeReason::kBadQuaternion: return "bad_quaternion";
    case DecodeReason::kBadValue: return "bad_value";
    case DecodeReason::kInternal: return "internal";
    case DecodeReason::kCount: break;
  }
  return "invalid_reason";
}

DecodeStats& DecodeStats::Global() {
  static DecodeStats stats;
  return stats;
}

uint64_t DecodeStats::Rejected() const {
  uint64_t n = 0;
  for (int i = 1; i < static_cast<int>(DecodeReason::kCount); ++i) {
    n += counts_[i].load(std::memory_order_relaxed);
  }
  return n;
}

std::map<std::string, uint64_t> DecodeStats::Snapshot() const {
  std::map<std::string, uint64_t> out;
  for (int i = 0; i < static_cast<int>(DecodeReason::kCount); ++i) {
    out[DecodeReasonName(static_cast<DecodeReason>(i))] = counts_[i].load(std::memory_order_relaxed);
  }
  return out;
}

void DecodeStats::Reset() {
  for (auto& c : counts_) c.store(0, std::memory_order_relaxed);
}

}  // namespace p2i::msgs
