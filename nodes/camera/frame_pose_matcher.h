/// @file frame_pose_matcher.h
/// @brief Gives live frames their pose from the pose stream by timestamp: holds frames that
/// wait for a newer pose (bounded, for a bounded time), drops and counts those that get none.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "nodes/camera/live_backend.h"
#include "scene/pose_stream.h"

namespace p2i::nodes {

/// A frame with the pose interpolated at its stamp.
struct MatchedFrame {
  LiveFrame frame;
  scene::Pose pose;
};

/// Frames arrive with AddFrame, poses with AddPose; Poll returns the frames that got a pose, in
/// arrival order. A frame is dropped when its lookup cannot succeed any more (too old for the
/// pose buffer, or the bracketing poses are beyond `tolerance`), when it waited longer than
/// `max_wait` for a newer pose, or when `max_pending` frames already wait (the oldest goes).
///
/// Thread-safety: thread-compatible (the camera node uses it on its executor thread only).
class FramePoseMatcher {
 public:
  struct Options {
    int64_t tolerance_ns = 50'000'000;  ///< both bracketing poses within this of the stamp
    int64_t max_wait_ns = 200'000'000;  ///< how long a frame may wait for a newer pose
    size_t max_pending = 8;             ///< frames held at most
    size_t pose_capacity = 1024;        ///< poses kept
  };
  struct Counters {
    uint64_t matched = 0;
    uint64_t dropped_too_old = 0;   ///< older than every pose kept
    uint64_t dropped_gap = 0;       ///< bracketed, but a pose is farther than the tolerance
    uint64_t dropped_timeout = 0;   ///< waited max_wait for a newer pose (or for any pose)
    uint64_t dropped_overflow = 0;  ///< max_pending frames were already waiting
    uint64_t poses_duplicate = 0;   ///< a pose stamp seen before (replaced)
    uint64_t poses_too_old = 0;     ///< older than everything kept (ignored)
    uint64_t dropped() const {
      return dropped_too_old + dropped_gap + dropped_timeout + dropped_overflow;
    }
  };

  explicit FramePoseMatcher(const Options& options);

  void AddPose(int64_t stamp_ns, const scene::Pose& pose);
  /// `now_ns` is the arrival time (any clock; Poll must use the same one).
  void AddFrame(LiveFrame&& frame, int64_t now_ns);
  /// Frames matched since the last call (oldest first); drops what cannot match any more.
  std::vector<MatchedFrame> Poll(int64_t now_ns);

  const Counters& counters() const { return counters_; }
  size_t pending() const { return pending_.size(); }
  const scene::PoseStream& poses() const { return poses_; }
  const Options& options() const { return options_; }

 private:
  struct Pending {
    LiveFrame frame;
    int64_t arrived_ns;
  };
  Options options_;
  scene::PoseStream poses_;
  std::deque<Pending> pending_;
  Counters counters_;
};

}  // namespace p2i::nodes
