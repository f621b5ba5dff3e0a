/// @file sequence_tracker.h
/// @brief Per-source sequence-number accounting: which messages were lost, duplicated or late.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace p2i::slam_sink {

/// The accounting of one source (publisher).
struct SourceAccount {
  uint64_t first_seq = 0;
  uint64_t last_seq = 0;   ///< the highest seq seen
  uint64_t received = 0;   ///< distinct seq numbers received
  uint64_t duplicates = 0;
  uint64_t late = 0;       ///< arrived after a higher seq (filled a gap)
  uint64_t before_first = 0;  ///< arrived with a seq below the first one seen (not tracked)
  std::set<uint64_t> missing;  ///< seq numbers in [first_seq, last_seq] never received

  /// Missing seq numbers as inclusive ranges, e.g. {{4,4},{9,12}}.
  std::vector<std::pair<uint64_t, uint64_t>> MissingRanges() const;
};

/// Tracks the sequence numbers of each source. A source's window starts at the first seq it is
/// seen with (messages published before the sink subscribed are not "lost"); every number
/// between that and the highest one seen that never arrived is missing. A late arrival removes
/// its number from the missing set. A publisher restart (a seq <= `restart_threshold` that was
/// already received or lies before the window, while the highest seen is more than
/// `restart_threshold` above it) starts a new epoch: the source is then tracked as
/// "<source>#<epoch>" so the old epoch's accounting is kept. When publish stamps are given, a
/// seq at or below the highest one seen whose publish stamp is newer than every stamp of the
/// epoch is a restart too, whatever its number: one publisher sends in order, so only a new
/// process can send a lower number later (a respawned node whose first messages were lost to
/// the subscriber's reconnect would otherwise look like a run of duplicates and be discarded).
/// A latched re-publication carries its original stamp and stays a duplicate.
///
/// Thread-compatible.
class SequenceTracker {
 public:
  /// What Observe() concluded about one message.
  enum class Outcome { kFirst, kInOrder, kAfterGap, kLate, kDuplicate, kRestart, kBeforeFirst };

  explicit SequenceTracker(uint64_t restart_threshold = 2);

  /// Records (source, seq); `gap` (optional) receives how many numbers were skipped just now.
  /// `publish_stamp_ns` (0 = unknown) is the header's publish stamp (restart detection).
  Outcome Observe(const std::string& source, uint64_t seq, uint64_t* gap = nullptr,
                  int64_t publish_stamp_ns = 0);

  /// Accounts keyed by source name ("<source>#<epoch>" for epochs after a restart).
  const std::map<std::string, SourceAccount>& accounts() const { return accounts_; }
  uint64_t TotalMissing() const;
  uint64_t TotalReceived() const;

  /// Whether (source, seq) was received (duplicates included). Only the current epoch.
  bool WasReceived(const std::string& source, uint64_t seq) const;

 private:
  std::string CurrentKey(const std::string& source) const;

  uint64_t restart_threshold_;
  std::map<std::string, SourceAccount> accounts_;
  std::map<std::string, int> epochs_;                  // source -> current epoch
  std::map<std::string, std::set<uint64_t>> seen_;    // current key -> received seq numbers
  std::map<std::string, int64_t> newest_stamp_;        // current key -> newest publish stamp
};

}  // namespace p2i::slam_sink
