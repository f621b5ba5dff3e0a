/// @file sequence_tracker.cc
/// @brief SequenceTracker.
#include "nodes/slam_sink/sequence_tracker.h"

#include <algorithm>
#include <numeric>

namespace p2i::slam_sink {

std::vector<std::pair<uint64_t, uint64_t>> SourceAccount::MissingRanges() const {
  std::vector<std::pair<uint64_t, uint64_t>> ranges;
  for (uint64_t seq : missing) {
    if (!ranges.empty() && ranges.back().second + 1 == seq) {
      ranges.back().second = seq;
    } else {
      ranges.emplace_back(seq, seq);
    }
  }
  return ranges;
}

SequenceTracker::SequenceTracker(uint64_t restart_threshold)
    : restart_threshold_(restart_threshold) {}

std::string SequenceTracker::CurrentKey(const std::string& source) const {
  const auto it = epochs_.find(source);
  if (it == epochs_.end() || it->second == 0) return source;
  return source + "#" + std::to_string(it->second);
}

SequenceTracker::Outcome SequenceTracker::Observe(const std::string& source, uint64_t seq,
                                                  uint64_t* gap, int64_t publish_stamp_ns) {
  if (gap != nullptr) *gap = 0;
  std::string key = CurrentKey(source);
  auto it = accounts_.find(key);
  Outcome restart_outcome = Outcome::kFirst;
  if (it != accounts_.end()) {
    SourceAccount& account = it->second;
    // A restarted publisher counts from 0 (or 1) again: a new epoch, not a flood of "late".
    const bool seen_before = seq < account.first_seq || seen_[key].count(seq) > 0;
    const auto newest = newest_stamp_.find(key);
    const bool newer_stamp = publish_stamp_ns > 0 && newest != newest_stamp_.end() &&
                             newest->second > 0 && publish_stamp_ns > newest->second;
    if ((seen_before && seq <= restart_threshold_ &&
         account.last_seq > seq + restart_threshold_) ||
        (newer_stamp && seq <= account.last_seq)) {
      ++epochs_[source];
      key = CurrentKey(source);
      it = accounts_.end();
      restart_outcome = Outcome::kRestart;
    }
  }
  if (it == accounts_.end()) {
    SourceAccount account;
    account.first_seq = account.last_seq = seq;
    account.received = 1;
    accounts_[key] = account;
    seen_[key].insert(seq);
    newest_stamp_[key] = publish_stamp_ns;
    return restart_outcome;
  }
  SourceAccount& account = it->second;
  std::set<uint64_t>& seen = seen_[key];
  int64_t& newest_stamp = newest_stamp_[key];
  newest_stamp = std::max(newest_stamp, publish_stamp_ns);
  if (seq < account.first_seq) {
    ++account.before_first;
    return Outcome::kBeforeFirst;
  }
  if (!seen.insert(seq).second) {
    ++account.duplicates;
    return Outcome::kDuplicate;
  }
  ++account.received;
  if (seq > account.last_seq) {
    const uint64_t skipped = seq - account.last_seq - 1;
    // Bound the bookkeeping of absurd jumps (a corrupt seq): record at most 1e6 numbers.
    const uint64_t recorded = std::min<uint64_t>(skipped, 1000000);
    for (uint64_t s = account.last_seq + 1; s < account.last_seq + 1 + recorded; ++s) {
      account.missing.insert(s);
    }
    account.last_seq = seq;
    if (gap != nullptr) *gap = skipped;
    return skipped > 0 ? Outcome::kAfterGap : Outcome::kInOrder;
  }
  account.missing.erase(seq);
  ++account.late;
  return Outcome::kLate;
}

uint64_t SequenceTracker::TotalMissing() const {
  uint64_t n = 0;
  for (const auto& [key, account] : accounts_) n += account.missing.size();
  return n;
}

uint64_t SequenceTracker::TotalReceived() const {
  uint64_t n = 0;
  for (const auto& [key, account] : accounts_) n += account.received;
  return n;
}

bool SequenceTracker::WasReceived(const std::string& source, uint64_t seq) const {
  const auto it = seen_.find(CurrentKey(source));
  return it != seen_.end() && it->second.count(seq) > 0;
}

}  // namespace p2i::slam_sink
