/// @file pose_stream.h
/// @brief A bounded, time-ordered buffer of stamped poses and the pose at any stamp between two
/// of them (translation lerp + rotation SLERP): how live camera frames get their pose.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "scene/pose.h"

namespace p2i::scene {

/// Why a lookup gave no pose (kOk when it did).
enum class PoseLookupStatus {
  kOk,
  kEmpty,      ///< no pose received yet (a newer pose may still come: wait)
  kTooOld,     ///< the stamp is older than the oldest pose kept (never answerable: drop)
  kNotYet,     ///< the stamp is newer than the newest pose (a newer pose may come: wait)
  kGapTooBig,  ///< bracketed, but a bracketing pose is farther than the tolerance (drop)
};

/// A short name ("ok", "empty", "too_old", "not_yet", "gap_too_big") for logs and counters.
const char* ToString(PoseLookupStatus status);

struct PoseLookup {
  PoseLookupStatus status = PoseLookupStatus::kEmpty;
  std::optional<Pose> pose;  ///< set iff status == kOk
  /// The bracketing stamps used or found (0 when not applicable), for diagnostics.
  int64_t before_ns = 0, after_ns = 0;
  bool ok() const { return status == PoseLookupStatus::kOk; }
  /// One line for a log: the status and the stamps involved.
  std::string Describe(int64_t stamp_ns) const;
};

/// Poses keyed by stamp (nanoseconds, any epoch shared with the lookups), kept sorted whatever
/// order they arrive in, at most `capacity` of them (the oldest are evicted).
///
/// Lookup(stamp, tolerance): an exact stamp gives its pose; otherwise the two poses bracketing
/// the stamp, if both are within `tolerance` of it, give the interpolation at
/// alpha = (stamp - before) / (after - before); otherwise the status says why not.
///
/// Thread-safety: thread-compatible (a value type; no internal locking).
class PoseStream {
 public:
  /// What Add() did with a pose.
  enum class AddResult {
    kAdded,
    kDuplicate,  ///< the same stamp was already there: the new pose replaced it
    kTooOld,     ///< older than everything kept while full: ignored
  };

  /// `capacity` >= 2 (std::invalid_argument otherwise).
  explicit PoseStream(size_t capacity = 1024);

  AddResult Add(int64_t stamp_ns, const Pose& pose);
  PoseLookup Lookup(int64_t stamp_ns, int64_t tolerance_ns) const;

  size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  size_t capacity() const { return capacity_; }
  /// Stamps of the oldest / newest pose kept; 0 when empty.
  int64_t oldest_ns() const { return poses_.empty() ? 0 : poses_.front().stamp_ns; }
  int64_t newest_ns() const { return poses_.empty() ? 0 : poses_.back().stamp_ns; }
  void Clear() { poses_.clear(); }

 private:
  struct Entry {
    int64_t stamp_ns;
    Pose pose;
  };
  size_t capacity_;
  std::deque<Entry> poses_;
};

}  // namespace p2i::scene
