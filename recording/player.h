/// @file player.h
/// @brief Republishes an MCAP recording on its p2i topics with the recorded timing
/// (`p2i play`): rate factor, loop, topic filter, start offset.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nodes/runtime/raw_publisher.h"

namespace p2i::recording {

struct PlayerOptions {
  std::string input;                ///< FILE.mcap (required)
  double rate = 1.0;                ///< speed factor (2 = twice as fast), > 0
  bool loop = false;                ///< start again at the end (until stopped)
  std::vector<std::string> topics;  ///< only these recorded topics (empty = every p2i channel)
  double start_s = 0.0;             ///< skip the first S seconds of the recording
  /// Wait this long after binding the publishers before the first message, so subscribers that
  /// are already running connect (ZeroMQ drops what is sent before they have).
  double delay_s = 0.5;
  std::string node_name = "/p2i_play";  ///< header.publisher of republished messages
  /// Topics of these types are latched (re-sent every latch_period_s for late joiners).
  std::vector<std::string> latched_types = {"p2i.msgs.pb.CameraInfo", "p2i.msgs.pb.ModelVersion"};
  double latch_period_s = 1.0;
  /// Throws std::invalid_argument naming the option and how to fix it.
  void Validate() const;
};

struct PlayerStats {
  uint64_t published = 0;
  uint64_t skipped = 0;     ///< filtered out (topic, before start_s) or not p2i channels
  uint64_t unreadable = 0;  ///< recorded data that did not convert back (counted, dropped)
  int loops = 0;
  std::string stop_reason;  ///< from the reader when the file ended early (killed recorder)
};

/// Not thread-safe except Stats(). Stops at the end (unless loop) or on runtime::Shutdown.
class Player {
 public:
  explicit Player(PlayerOptions options);
  /// Plays; returns false + error if the file cannot be read. `on_publish` (optional) is
  /// called after each message with its scheduled and actual wall times in ns (bench).
  using PublishHook = std::function<void(const std::string& topic, int64_t scheduled_ns,
                                         int64_t actual_ns)>;
  bool Run(std::string* error, const PublishHook& on_publish = {});
  const PlayerStats& Stats() const { return stats_; }

 private:
  PlayerOptions options_;
  PlayerStats stats_;
};

}  // namespace p2i::recording
