/// @file sequence_tracker_test.cc
/// @brief SequenceTracker: gaps, late arrivals, duplicates, restarts, several sources.
#include "nodes/slam_sink/sequence_tracker.h"

#include <catch2/catch.hpp>

namespace p2i::slam_sink {
namespace {

using Outcome = SequenceTracker::Outcome;

TEST_CASE("SequenceTracker reports exactly the lost sequence numbers", "[unit]") {
  SequenceTracker tracker;
  uint64_t gap = 99;
  CHECK(tracker.Observe("/a", 10, &gap) == Outcome::kFirst);  // window starts here
  CHECK(gap == 0);
  CHECK(tracker.Observe("/a", 11, &gap) == Outcome::kInOrder);
  CHECK(tracker.Observe("/a", 14, &gap) == Outcome::kAfterGap);
  CHECK(gap == 2);
  CHECK(tracker.Observe("/a", 15) == Outcome::kInOrder);
  CHECK(tracker.Observe("/a", 20, &gap) == Outcome::kAfterGap);
  CHECK(gap == 4);
  CHECK(tracker.Observe("/a", 17) == Outcome::kLate);  // fills part of the gap
  CHECK(tracker.Observe("/a", 17) == Outcome::kDuplicate);
  CHECK(tracker.Observe("/a", 3) == Outcome::kBeforeFirst);

  const SourceAccount& a = tracker.accounts().at("/a");
  CHECK(a.first_seq == 10);
  CHECK(a.last_seq == 20);
  CHECK(a.received == 6);
  CHECK(a.duplicates == 1);
  CHECK(a.late == 1);
  CHECK(a.before_first == 1);
  CHECK(a.missing == std::set<uint64_t>{12, 13, 16, 18, 19});
  const auto ranges = a.MissingRanges();
  REQUIRE(ranges.size() == 3);
  CHECK(ranges[0] == std::make_pair<uint64_t, uint64_t>(12, 13));
  CHECK(ranges[1] == std::make_pair<uint64_t, uint64_t>(16, 16));
  CHECK(ranges[2] == std::make_pair<uint64_t, uint64_t>(18, 19));
  CHECK(tracker.TotalMissing() == 5);
  CHECK(tracker.WasReceived("/a", 17));
  CHECK_FALSE(tracker.WasReceived("/a", 16));
}

TEST_CASE("SequenceTracker keeps sources apart and treats a publisher restart as a new epoch",
          "[unit]") {
  SequenceTracker tracker;
  for (uint64_t s : {0, 1, 2, 4, 5, 6, 7, 8}) tracker.Observe("/synth", s);
  for (uint64_t s : {100, 101, 103}) tracker.Observe("/camera", s);
  // The synthesizer respawns and counts from 0 again.
  CHECK(tracker.Observe("/synth", 0) == Outcome::kRestart);
  CHECK(tracker.Observe("/synth", 2) == Outcome::kAfterGap);

  const auto& accounts = tracker.accounts();
  REQUIRE(accounts.count("/synth") == 1);
  REQUIRE(accounts.count("/synth#1") == 1);
  CHECK(accounts.at("/synth").missing == std::set<uint64_t>{3});
  CHECK(accounts.at("/synth#1").missing == std::set<uint64_t>{1});
  CHECK(accounts.at("/camera").missing == std::set<uint64_t>{102});
  CHECK(tracker.TotalMissing() == 3);
  CHECK(tracker.TotalReceived() == 8 + 3 + 2);
}

TEST_CASE("SequenceTracker detects a restart by its newer publish stamp even when the first "
          "messages after it were lost", "[unit]") {
  SequenceTracker tracker;
  int64_t t = 1000;
  for (uint64_t s = 1; s <= 10; ++s) tracker.Observe("/synth", s, nullptr, t += 10);
  // A latched re-publication: same seq, its original stamp -> duplicate.
  CHECK(tracker.Observe("/synth", 10, nullptr, t) == Outcome::kDuplicate);
  // An old message arriving late keeps its old stamp -> duplicate, not a restart.
  CHECK(tracker.Observe("/synth", 4, nullptr, 1040) == Outcome::kDuplicate);
  // The publisher respawns; its seq 1..3 never reached us (reconnect): 4 is the first we see.
  uint64_t gap = 99;
  CHECK(tracker.Observe("/synth", 4, &gap, t += 1000) == Outcome::kRestart);
  CHECK(tracker.Observe("/synth", 5, &gap, t += 10) == Outcome::kInOrder);
  CHECK(tracker.Observe("/synth", 7, &gap, t += 10) == Outcome::kAfterGap);
  CHECK(gap == 1);
  const auto& accounts = tracker.accounts();
  REQUIRE(accounts.count("/synth#1") == 1);
  CHECK(accounts.at("/synth").received == 10);
  CHECK(accounts.at("/synth").duplicates == 2);
  CHECK(accounts.at("/synth#1").first_seq == 4);
  CHECK(accounts.at("/synth#1").received == 3);
  CHECK(accounts.at("/synth#1").missing == std::set<uint64_t>{6});
  // Without stamps the same sequence would have been discarded as duplicates.
  SequenceTracker no_stamps;
  for (uint64_t s = 1; s <= 10; ++s) no_stamps.Observe("/synth", s);
  CHECK(no_stamps.Observe("/synth", 4) == Outcome::kDuplicate);
}

}  // namespace
}  // namespace p2i::slam_sink
